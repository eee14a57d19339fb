// One-sided scatter-as-gather 1D blur of the hexagon (blur() in kernels/hexagon/hexagon.cpp) for the
// OUTPUTS adjacent pixels (x0 + j, y), reading the RGBA buffer BLUR_SOURCE: defines
//   void BLUR_NAME(int x0, int y, int direction, float centre_coc[OUTPUTS], out BlurSums sums[OUTPUTS]).
// Included once per source buffer (GLSL cannot pass a buffer to a function). Needs TAPS, OUTPUTS,
// common.glsl, bilinear.glsl and hexagon.glsl. An off-axis tap has the same offset for every pixel, so
// the pixels share its texels: 2 (OUTPUTS + 1) loads instead of 4 OUTPUTS. Taps off the image add 0
// (their loads stay clamped: no branch).
void BLUR_NAME(int x0, int y, const int direction, float centre_coc[OUTPUTS], out BlurSums sums[OUTPUTS]) {
  const uint row = uint(y * params.width_px);
  for (int j = 0; j < OUTPUTS; ++j) {
    const vec4 centre = BLUR_SOURCE[row + uint(clamp_x(x0 + j))];
    sums[j] = blur_start();
    blur_add(sums[j], centre, hexagon_centre_weight(centre.a), 1.0);  // t = 0: the pixel itself
  }
  for (int t = 1; t <= TAPS; ++t) {
    const float ft = float(t);
    if (direction == HEX_UP && HEX_UP_ON_AXIS != 0) {
      const bool inside = y + t <= params.height_px - 1;
      const uint tap_row = uint(clamp_y(y + t) * params.width_px);
      for (int j = 0; j < OUTPUTS; ++j) {
        const vec4 s = BLUR_SOURCE[tap_row + uint(clamp_x(x0 + j))];
        blur_add(sums[j], s, inside ? hexagon_coverage(s.a, ft) : 0.0, hexagon_rule(s.a, centre_coc[j]));
      }
    } else {
      precise const vec2 d = ft * hex_direction(direction);  // (ft gx, ft gy): the CPU's products
      precise const vec2 whole_f = floor(d);
      precise const vec2 f = d - whole_f;  // split_offset()
      const ivec2 whole = ivec2(whole_f);
      const int sy = y + whole.y;
      const uint row0 = uint(clamp_y(sy) * params.width_px), row1 = uint(clamp_y(sy + 1) * params.width_px);
      vec4 top[OUTPUTS + 1], bottom[OUTPUTS + 1];
      for (int k = 0; k <= OUTPUTS; ++k) {
        const uint sx = uint(clamp_x(x0 + whole.x + k));
        top[k] = BLUR_SOURCE[row0 + sx];
        bottom[k] = BLUR_SOURCE[row1 + sx];
      }
      const vec4 beta = bilinear_weights(f);
      for (int j = 0; j < OUTPUTS; ++j) {
        const vec4 b = sample_inside(ivec2(x0 + j + whole.x, sy), f) ? beta : vec4(0.0);
        const float c = centre_coc[j];
        blur_add(sums[j], top[j], b.x * hexagon_coverage(top[j].a, ft), hexagon_rule(top[j].a, c));
        blur_add(sums[j], top[j + 1], b.y * hexagon_coverage(top[j + 1].a, ft), hexagon_rule(top[j + 1].a, c));
        blur_add(sums[j], bottom[j], b.z * hexagon_coverage(bottom[j].a, ft), hexagon_rule(bottom[j].a, c));
        blur_add(sums[j], bottom[j + 1], b.w * hexagon_coverage(bottom[j + 1].a, ft), hexagon_rule(bottom[j + 1].a, c));
      }
    }
  }
}
