#version 450
// Naive quadratic gather (paper 3.1): all N x N samples at spacing k, disc test, sum.
//
// OUTPUTS_X x OUTPUTS_Y (specialisation constants 0 and 1) outputs per invocation, at stride k:
// outputs (x0 + m k, y0 + l k). Samples lie on the same lattice, so each loaded sample serves up
// to OUTPUTS_X x OUTPUTS_Y outputs. Every output still adds its samples row by row, left to right:
// the same sums in the same order as the 1 x 1 shader, bit for bit. Rows and columns outside the
// pattern's largest disc (radius max_radius_px, which the CoC pass clamps every radius to) are
// skipped: no radius reaches them, so skipping changes nothing.
//
// Why blocks: lavapipe turns every per-invocation buffer load into a scalar load per lane, so a
// pass costs its number of loads; an 8 x 4 block loads about (2n + 11)(2n + 4) samples for 32
// outputs instead of 32 (2n + 1)^2. On a real GPU the L1 cache already serves neighbouring
// invocations' loads, the strided mapping spreads a warp's loads over more cache lines and a
// block holds 3 x 32 sums in registers: the method option gather_block picks 1 x 1, the plain
// shader, there unless told otherwise (kernels/naive/naive_gpu.hpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int OUTPUTS_X = 1;
layout(constant_id = 1) const int OUTPUTS_Y = 1;

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };

// The previous, straightforward shader: one output, every pattern sample.
void gather_one(ivec2 p) {
  const int n = params.half_n, k = params.spacing_px;
  vec3 sum = vec3(0.0);
  for (int j = -n; j <= n; ++j) {
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    for (int i = -n; i <= n; ++i) {
      const int sx = p.x + i * k;
      if (sx < 0 || sx >= params.width_px) continue;
      const vec4 s = packed_input[index_of(ivec2(sx, sy))];
      if (in_disc(s.a * s.a, i * k, j * k)) sum += s.rgb;
    }
  }
  result[index_of(p)] = vec4(sum, 1.0);
}

// Largest |i| of pattern row j inside the largest disc (uniform), or -1 if the row is outside it
// or outside the pattern. A sample that fails in_disc at the largest radius fails it at every
// smaller one (in_disc is monotonic in radius_sq), so the skipped samples add nothing.
int row_reach(int j) {
  const int n = params.half_n;
  if (j < -n || j > n) return -1;
  const float max_r2 = params.max_radius_px * params.max_radius_px;
  return disc_reach_layer(max_r2, abs(j) * params.spacing_px, params.spacing_px, n);
}

void main() {
  if (OUTPUTS_X == 1 && OUTPUTS_Y == 1) {
    const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!outside(p)) gather_one(p);
    return;
  }
  const int n = params.half_n, k = params.spacing_px;
  // Invocation g covers block g / k of OUTPUTS k columns, phase g % k (likewise for rows).
  const ivec2 g = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 p0 = ivec2((g.x / k) * (OUTPUTS_X * k) + g.x % k, (g.y / k) * (OUTPUTS_Y * k) + g.y % k);
  if (outside(p0)) return;
  vec3 sum[OUTPUTS_Y][OUTPUTS_X];
  for (int l = 0; l < OUTPUTS_Y; ++l)
    for (int m = 0; m < OUTPUTS_X; ++m) sum[l][m] = vec3(0.0);
  // j: sample row relative to p0; output row l sees it as pattern row j - l.
  for (int j = -n; j < n + OUTPUTS_Y; ++j) {
    const int sy = p0.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    int reach[OUTPUTS_Y];
    int span = -1;
    for (int l = 0; l < OUTPUTS_Y; ++l) {
      reach[l] = row_reach(j - l);
      span = max(span, reach[l]);
    }
    if (span < 0) continue;
    for (int i = -span; i < span + OUTPUTS_X; ++i) {
      const int sx = p0.x + i * k;
      if (sx < 0 || sx >= params.width_px) continue;
      const vec4 s = packed_input[index_of(ivec2(sx, sy))];
      const float r2 = s.a * s.a;
      for (int l = 0; l < OUTPUTS_Y; ++l)
        for (int m = 0; m < OUTPUTS_X; ++m) {
          const int di = i - m;
          if (di < -reach[l] || di > reach[l]) continue;  // uniform: outside the largest disc
          if (in_disc(r2, di * k, (j - l) * k)) sum[l][m] += s.rgb;
        }
    }
  }
  for (int l = 0; l < OUTPUTS_Y; ++l)
    for (int m = 0; m < OUTPUTS_X; ++m) {
      const ivec2 p = p0 + ivec2(m, l) * k;
      if (!outside(p)) result[index_of(p)] = vec4(sum[l][m], 1.0);
    }
}
