#version 450
// Radius-following circular filter: which 32 x 32 tiles each bucket's passes must visit (after
// layers.comp, before plan.comp; one invocation per tile, both fields). A bucket's horizontal
// response is exactly 0 in a tile whose row band holds no pixel of that bucket within the kernel
// radius R (reach = ceil(R / 32) tiles), and its vertical response is 0 where no such tile lies
// within the reach above or below; those tiles are skipped, which leaves the output unchanged.
//   STEP 0 (rows):    row[f][t] = bucket bits of the raw tile masks within each bucket's reach
//                     along the tile row (raw: layers.comp's per-tile bucket masks).
//   STEP 1 (columns): bucket k's vertical pass visits tile t if a row[f] tile with bit k lies within
//                     the reach along the column; its horizontal pass visits the tiles the vertical
//                     pass reads (within twice the reach), computing where row[f] has bit k and
//                     writing zeros elsewhere (entries with ZERO_TILE set). Appends to the lists
//                     with atomicAdd on their counts, which plan.comp turns into dispatch sizes.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "tiles.glsl"

layout(constant_id = 0) const int STEP = 0;
layout(constant_id = 1) const int BUCKETS = 1;

layout(std430, binding = 0) buffer TileState { uint tile_state[]; };  // see tiles.glsl
layout(std430, binding = 1) writeonly buffer TileLists { uint tile_list[]; };
layout(std140, binding = 2) uniform Buckets { vec4 ramp[32]; ivec4 reach[32]; } buckets;

void main() {
  const ivec2 grid = tile_grid(params.width_px, params.height_px), t = ivec2(gl_GlobalInvocationID.xy);
  if (t.x >= grid.x || t.y >= grid.y) return;
  const int tiles = grid.x * grid.y, index = t.y * grid.x + t.x;
  for (int f = 0; f < 2; ++f) {
    if (STEP == 0) {
      uint row = 0u;
      for (int k = 1; k <= BUCKETS; ++k) {
        const int reach = buckets.reach[k - 1][f];
        for (int x = max(t.x - reach, 0); x <= min(t.x + reach, grid.x - 1); ++x)
          row |= tile_state[raw_mask_at(f, t.y * grid.x + x, tiles)] & (1u << uint(k));
      }
      tile_state[row_mask_at(f, index, tiles)] = row;
    } else {
      for (int k = 1; k <= BUCKETS; ++k) {
        const uint bit = 1u << uint(k);
        const int reach = buckets.reach[k - 1][f];
        bool vertical = false, read = false;
        for (int y = max(t.y - 2 * reach, 0); y <= min(t.y + 2 * reach, grid.y - 1); ++y) {
          const bool row = (tile_state[row_mask_at(f, y * grid.x + t.x, tiles)] & bit) != 0u;
          read = read || row;
          vertical = vertical || (row && abs(y - t.y) <= reach);
        }
        const bool own = (tile_state[row_mask_at(f, index, tiles)] & bit) != 0u;
        const int list = tile_list_index(f, k, 0);
        if (read) tile_list[list * tiles + atomicAdd(tile_state[list], 1u)] = uint(index) | (own ? 0u : ZERO_TILE);
        if (vertical) tile_list[(list + 1) * tiles + atomicAdd(tile_state[list + 1], 1u)] = uint(index);
      }
    }
  }
}
