// Bilinear samples of the engine-style gathers (spiral, hexagon), which sample every pixel at the
// same offsets: an offset is split into whole pixels and a fraction (f), so the weights depend on the
// offset alone and adjacent pixels computed by one invocation share their texels. Mirrors
// kernels/core/signed_coc.hpp operation for operation; `precise` forbids fused multiply-adds so both
// sides round alike. GLSL cannot pass a buffer, so callers load the texels themselves.

// The interpolated value (all four channels, as a filtered texture gives them) of the texels
// (sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1).
vec4 bilinear_mix(vec2 f, vec4 v00, vec4 v10, vec4 v01, vec4 v11) {
  precise const float gx = 1.0 - f.x, gy = 1.0 - f.y;
  precise const vec4 top = v00 * gx + v10 * f.x;
  precise const vec4 bottom = v01 * gx + v11 * f.x;
  precise const vec4 v = top * gy + bottom * f.y;
  return v;
}

// The four texels' weights, in the same order.
vec4 bilinear_weights(vec2 f) {
  precise const float gx = 1.0 - f.x, gy = 1.0 - f.y;
  precise const vec4 w = vec4(gx * gy, f.x * gy, gx * f.y, f.x * f.y);
  return w;
}

// Whether the sample at whole pixel s plus fraction f lies within the outermost pixel centres; the
// gathers skip other samples (see sample_inside() in kernels/core/signed_coc.hpp).
bool sample_inside(ivec2 s, vec2 f) {
  return s.x >= 0 && s.y >= 0 && (s.x < params.width_px - 1 || (s.x == params.width_px - 1 && f.x == 0.0)) &&
         (s.y < params.height_px - 1 || (s.y == params.height_px - 1 && f.y == 0.0));
}

int clamp_x(int x) { return clamp(x, 0, params.width_px - 1); }
int clamp_y(int y) { return clamp(y, 0, params.height_px - 1); }
