#version 450
// FLAG vertical pass (paper 3.2.3): sum layer |j| of rows y + j k.
// BRACKETED=1: each texel is (v - offset) / scale of its row's bracket: read back offset + scale * q.
// ADAPTIVE=1 (method option adaptive = on): a pixel whose tile nothing blurred reaches (D = 0 in the
// tile-max CoC map, tiles.glsl) outputs its input; the others sum layers |j| <= min(isqrt(D), n)
// only: the layers above are 0 there (no source reaching the pixel reaches them), and adding +0.0
// changes no sum, so the output is the worst case's bit for bit. The horizontal pass wrote every
// layer read here (its Z covers what this tile reads).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "layer_rows.glsl"

layout(constant_id = 0) const int LAYERS = 21;
// Any aperture that is not mirror-symmetric (kernels/flag/flag_shape.hpp): N layers z = dz + n, and
// row y + j k holds the sources whose chord covers dz = -j: layer n - j. Else layer |j|.
layout(constant_id = 8) const bool BOTH_HALVES = false;
// The method's option vertical_order (kernels/flag/flag_gpu.hpp): true, workgroups walk down column
// strips, so the rows between a layer row's two reads (by rows y -+ j k) stay in cache.
layout(constant_id = 9) const bool COLUMN_ORDER = false;

layout(binding = 0, LAYER_FORMAT) uniform readonly image3D layers;
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };
#if BRACKETED
// As in layers.glsl: [y * LAYERS + z].rgb = min bits, [half + y * LAYERS + z].rgb = max bits.
layout(std430, binding = 2) readonly buffer Brackets { uvec4 bracket_bits[]; };
#endif
#if ADAPTIVE
#define TILE_PX_ID 1
#define TILES_BINDING (2 + BRACKETED)
#include "tiles.glsl"
layout(std430, binding = 3 + BRACKETED) readonly buffer Packed { vec4 packed_input[]; };  // FLAG's input
#endif

void main() {
  uvec2 g = gl_GlobalInvocationID.xy;
  if (COLUMN_ORDER) {
    // The i-th workgroup launched (row-major, as drivers launch them) takes tile (i / tiles_y, i % tiles_y).
    const uint launched = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    const uvec2 tile = uvec2(launched / gl_NumWorkGroups.y, launched % gl_NumWorkGroups.y);
    g = tile * gl_WorkGroupSize.xy + gl_LocalInvocationID.xy;
  }
  const ivec2 p = ivec2(g.x, band_row(int(g.y)));
#if ADAPTIVE
  // Before any invocation returns: D of this pixel's tile (-1 outside the frame), and the largest
  // over the subgroup (uniform).
  const int pixel_reach = tile_bounds_over(p, p).x;
  const int reach = subgroupMax(pixel_reach);
  if (reach < 0) return;  // no pixel of the frame
  const int rows = min(isqrt(reach), LAYERS - 1);
#endif
  if (outside_band(p)) return;
  const int n = params.half_n, k = params.spacing_px;
#if ADAPTIVE
  if (pixel_reach == 0) {
    // Nothing blurred reaches it: its input (the gather of its own sample, from +0).
    const vec4 s = packed_input[index_of(p)];
    result[index_of(p)] = vec4(vec3(0.0) + (in_disc(s.a * s.a, 0, 0) ? s.rgb : vec3(0.0)), 1.0);
    return;
  }
  const int pixel_rows = min(isqrt(pixel_reach), LAYERS - 1);
#else
  const int rows = n;
#endif
#if BRACKETED
  const uint h = uint(bracket_bits.length()) / 2u;
#endif
  vec3 sum = vec3(0.0);
  for (int j = -rows; j <= rows; ++j) {
#if ADAPTIVE
    if (abs(j) > pixel_rows) continue;  // 0 there: no source reaching this pixel reaches that layer
#endif
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    const vec3 q = imageLoad(layers, ivec3(p.x, layer_row(sy), BOTH_HALVES ? n - j : abs(j))).rgb;
#if BRACKETED
    const uint i = uint(sy * LAYERS + abs(j));
    const vec3 offset = uintBitsToFloat(bracket_bits[i].rgb);
    const vec3 scale = uintBitsToFloat(bracket_bits[h + i].rgb) - offset;
    sum += offset + scale * q;
#else
    sum += q;
#endif
  }
  result[index_of(p)] = vec4(sum, 1.0);
}
