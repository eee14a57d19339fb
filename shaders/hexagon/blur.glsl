// One-sided scatter-as-gather 1D blur of the hexagon (blur() in kernels/hexagon/hexagon.cpp), reading
// the RGBA buffer BLUR_SOURCE: defines BlurSums BLUR_NAME(ivec2 p, int direction, float centre_coc).
// Included once per source buffer (GLSL cannot pass a buffer to a function). Needs TAPS, common.glsl,
// bilinear.glsl and hexagon.glsl. Samples off the image add 0 (loads stay clamped, no branch).
BlurSums BLUR_NAME(ivec2 p, const int direction, float centre_coc) {
  BlurSums sums = blur_start();
  const vec4 centre = BLUR_SOURCE[index_of(p)];
  blur_add(sums, centre, hexagon_centre_weight(centre.a));  // t = 0: the pixel itself
  for (int t = 1; t <= TAPS; ++t) {
    const float ft = float(t);
    if (direction == HEX_UP) {
      const vec4 s = BLUR_SOURCE[clamped_index(p + ivec2(0, t))];
      blur_add(sums, s, p.y + t <= params.height_px - 1 ? hexagon_weight(s.a, centre_coc, ft) : 0.0);
    } else {
      precise const float dx = ft * HEX_SIN60, dy = ft * -0.5;
      precise const vec2 pos = vec2(p) + vec2(direction == HEX_DOWNLEFT ? dx : -dx, dy);
      const Bilinear b = bilinear_at(pos);
      const vec4 beta = b.inside ? bilinear_weights(b) : vec4(0.0);
      const vec4 s00 = BLUR_SOURCE[b.i00], s10 = BLUR_SOURCE[b.i10], s01 = BLUR_SOURCE[b.i01], s11 = BLUR_SOURCE[b.i11];
      blur_add(sums, s00, beta.x * hexagon_weight(s00.a, centre_coc, ft));
      blur_add(sums, s10, beta.y * hexagon_weight(s10.a, centre_coc, ft));
      blur_add(sums, s01, beta.z * hexagon_weight(s01.a, centre_coc, ft));
      blur_add(sums, s11, beta.w * hexagon_weight(s11.a, centre_coc, ft));
    }
  }
  return sums;
}
