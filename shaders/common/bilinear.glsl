// Bilinear samples at pixel coordinates (pixel centres at integers), as the engine-style gathers
// (spiral, hexagon) sample a linearly filtered texture. Mirrors kernels/core/signed_coc.hpp operation
// for operation; `precise` forbids fused multiply-adds so both sides round alike. GLSL cannot pass a
// buffer, so the caller loads the four texels:
//   const Bilinear b = bilinear_at(pos);
//   const vec4 v = bilinear_mix(b, src[b.i00], src[b.i10], src[b.i01], src[b.i11]);
// `inside`: pos lies within the outermost pixel centres; the gathers skip other samples (see there).
struct Bilinear {
  uint i00, i10, i01, i11;  // (x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1), clamped
  float fx, fy;
  bool inside;
};

Bilinear bilinear_at(vec2 pos) {
  precise const vec2 p0 = floor(pos);
  precise const vec2 f = pos - p0;
  const ivec2 i = ivec2(p0);
  const ivec2 hi = ivec2(params.width_px - 1, params.height_px - 1);
  const ivec2 a = clamp(i, ivec2(0), hi), b = clamp(i + 1, ivec2(0), hi);
  Bilinear r;
  r.i00 = index_of(a);
  r.i10 = index_of(ivec2(b.x, a.y));
  r.i01 = index_of(ivec2(a.x, b.y));
  r.i11 = index_of(b);
  r.fx = f.x;
  r.fy = f.y;
  r.inside = all(greaterThanEqual(pos, vec2(0.0))) && all(lessThanEqual(pos, vec2(hi)));
  return r;
}

// The interpolated value (all four channels, as a filtered texture gives them).
vec4 bilinear_mix(Bilinear b, vec4 v00, vec4 v10, vec4 v01, vec4 v11) {
  precise const float gx = 1.0 - b.fx, gy = 1.0 - b.fy;
  precise const vec4 top = v00 * gx + v10 * b.fx;
  precise const vec4 bottom = v01 * gx + v11 * b.fx;
  precise const vec4 v = top * gy + bottom * b.fy;
  return v;
}

// The four texels' weights, in texel order.
vec4 bilinear_weights(Bilinear b) {
  precise const float gx = 1.0 - b.fx, gy = 1.0 - b.fy;
  precise const vec4 w = vec4(gx * gy, b.fx * gy, gx * b.fy, b.fx * b.fy);
  return w;
}

// The pixel p clamped to the image, for axis-aligned taps (one load).
uint clamped_index(ivec2 p) { return index_of(clamp(p, ivec2(0), ivec2(params.width_px - 1, params.height_px - 1))); }
