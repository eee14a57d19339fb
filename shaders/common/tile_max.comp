#version 450
// Tile-max CoC map, pass 1 (kernels/core/coc_tiles.hpp): per tile, M = the largest disc index of its
// pixels (from the packed input's radius, with the gathers' disc_index and cap 2 n^2).
// One invocation per tile: few invocations, each a loop of TILE_PX^2 loads.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int SPACING = 1;  // k, a constant divisor for disc_index
// The input's .a is a polygon's area (shape_pack's chord-table row, FLAG's fused pass for shapes):
// M is then the tile's largest area, not a disc index.
layout(constant_id = 2) const bool AREAS = false;
#define TILE_PX_ID 1
#define TILES_BINDING 1
#define TILES_ACCESS writeonly
#define TILES_WRITE_ONLY
#include "tiles.glsl"

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };

void main() {
  const ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  if (t.x >= tiles_x() || t.y >= tiles_y()) return;
  const ivec2 lo = t * TILE_PX, hi = min(lo + TILE_PX, ivec2(params.width_px, params.height_px));
  const int cap = 2 * params.half_n * params.half_n;
  int m = 0;
  for (int y = lo.y; y < hi.y; ++y)
    for (int x = lo.x; x < hi.x; ++x) {
      const float r = packed_input[index_of(ivec2(x, y))].a;
      m = max(m, AREAS ? int(r) : disc_index(r * r, SPACING, cap));
    }
  tiles[tile_element(t)].x = m;
}
