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

#if ADAPTIVE
// Adaptive mode (method option adaptive = on): the tile-max CoC map (tiles.glsl) gives every
// subgroup the largest disc index D that reaches any of its outputs; each output gathers only the
// samples with i^2 + j^2 <= D, in the same order, so it adds exactly what the whole pattern adds.
// D is the same in every lane (subgroupMax), so the loops run in step and the skip below is a
// uniform branch. D = 0 (nothing blurred reaches the subgroup): each output is its own sample, i.e.
// its input.
#define TILE_PX_ID 2
#define TILES_BINDING 2
#include "tiles.glsl"
#endif

// The previous, straightforward shader: one output, every pattern sample (adaptive: every sample
// inside the disc of index `reach`, which holds every sample that adds anything).
void gather_one(ivec2 p, int reach) {
  const int n = params.half_n, k = params.spacing_px;
  vec3 sum = vec3(0.0);
#if ADAPTIVE
  const int rows = reach_layer(reach, 0, n);
  for (int j = -rows; j <= rows; ++j) {
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    const int columns = reach_layer(reach, j, n);
    for (int i = -columns; i <= columns; ++i) {
#else
  for (int j = -n; j <= n; ++j) {
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    for (int i = -n; i <= n; ++i) {
#endif
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
// Adaptive: likewise inside the disc of index `reach` (uniform too).
int row_reach(int j, int reach) {
  const int n = params.half_n;
  if (j < -n || j > n) return -1;
#if ADAPTIVE
  return reach_layer(reach, j, n);
#else
  const float max_r2 = params.max_radius_px * params.max_radius_px;
  return disc_reach_layer(max_r2, abs(j) * params.spacing_px, params.spacing_px, n);
#endif
}

void main() {
  const int n = params.half_n, k = params.spacing_px;
  // Invocation g covers block g / k of OUTPUTS k columns, phase g % k (likewise for rows).
  const ivec2 g = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 p0 = ivec2((g.x / k) * (OUTPUTS_X * k) + g.x % k, (g.y / k) * (OUTPUTS_Y * k) + g.y % k);
#if ADAPTIVE
  // Before any invocation returns: the largest D over the tiles of the subgroup's outputs.
  const int reach = subgroup_tile_bounds(p0, p0 + ivec2(OUTPUTS_X - 1, OUTPUTS_Y - 1) * k).x;
  if (reach < 0) return;  // no output of the subgroup is in the frame
  const bool pass_through = reach == 0;
#else
  const int reach = 0;
  const bool pass_through = false;
#endif
  if (OUTPUTS_X == 1 && OUTPUTS_Y == 1) {
    const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (outside(p)) return;
    if (pass_through) {
      // What the gather gives when only the pixel's own sample can reach it (the sum starts at +0).
      const vec4 s = packed_input[index_of(p)];
      result[index_of(p)] = vec4(vec3(0.0) + (in_disc(s.a * s.a, 0, 0) ? s.rgb : vec3(0.0)), 1.0);
      return;
    }
    gather_one(p, reach);
    return;
  }
  if (outside(p0)) return;
  if (pass_through) {
    for (int l = 0; l < OUTPUTS_Y; ++l)
      for (int m = 0; m < OUTPUTS_X; ++m) {
        const ivec2 p = p0 + ivec2(m, l) * k;
        if (outside(p)) continue;
        const vec4 s = packed_input[index_of(p)];
        result[index_of(p)] = vec4(vec3(0.0) + (in_disc(s.a * s.a, 0, 0) ? s.rgb : vec3(0.0)), 1.0);
      }
    return;
  }
  vec3 sum[OUTPUTS_Y][OUTPUTS_X];
  for (int l = 0; l < OUTPUTS_Y; ++l)
    for (int m = 0; m < OUTPUTS_X; ++m) sum[l][m] = vec3(0.0);
  // j: sample row relative to p0; output row l sees it as pattern row j - l.
#if ADAPTIVE
  const int rows = reach_layer(reach, 0, n);
#else
  const int rows = n;
#endif
  for (int j = -rows; j < rows + OUTPUTS_Y; ++j) {
    const int sy = p0.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    int row[OUTPUTS_Y];
    int span = -1;
    for (int l = 0; l < OUTPUTS_Y; ++l) {
      row[l] = row_reach(j - l, reach);
      span = max(span, row[l]);
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
          if (di < -row[l] || di > row[l]) continue;  // uniform: outside the largest disc
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
