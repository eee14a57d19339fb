// The tile-max CoC map (kernels/core/coc_tiles.hpp has the definitions; included after common.glsl).
// Element 0: .x = the scene's largest disc index (atomicMax, reset every frame). Tile t (row-major
// over the grid of params.width_px x params.height_px in TILE_PX squares) is element t + 1:
//   .x M: the largest disc index of its pixels;
//   .y D: the largest M of the tiles whose discs can reach it (a gather bounded by D adds what the
//         whole pattern adds; D = 0: the tile's output is its input);
//   .z Z: FLAG only, the highest layer a vertical pass reads from its rows, -1 if none.
// Set before including: TILE_PX_ID (its specialisation constant id), TILES_BINDING, and TILES_ACCESS
// (readonly by default).
#ifndef TILES_ACCESS
#define TILES_ACCESS readonly
#endif

layout(constant_id = TILE_PX_ID) const int TILE_PX = 16;
layout(std430, binding = TILES_BINDING) TILES_ACCESS buffer Tiles { ivec4 tiles[]; };

int tiles_x() { return (params.width_px + TILE_PX - 1) / TILE_PX; }
int tiles_y() { return (params.height_px + TILE_PX - 1) / TILE_PX; }
int tile_element(ivec2 tile) { return 1 + tile.y * tiles_x() + tile.x; }
int tile_element_of(ivec2 p) { return tile_element(p / TILE_PX); }

// ceil(gap / k) for the pixel gap between tiles d tiles apart: (|d| - 1) TILE_PX + 1, 0 for d = 0.
int gap_samples(int d, int spacing_px) {
  return d == 0 ? 0 : ((abs(d) - 1) * TILE_PX + spacing_px) / spacing_px;
}

#ifndef TILES_WRITE_ONLY
#extension GL_KHR_shader_subgroup_arithmetic : require

// The largest .y (D) and .z (Z) over the tiles holding pixels [lo, hi] (clipped to the frame);
// (-1, -1) when the rectangle holds no pixel.
ivec2 tile_bounds_over(ivec2 lo, ivec2 hi) {
  hi = min(hi, ivec2(params.width_px, params.height_px) - 1);
  ivec2 bounds = ivec2(-1);
  for (int ty = lo.y / TILE_PX; ty <= hi.y / TILE_PX; ++ty)
    for (int tx = lo.x / TILE_PX; tx <= hi.x / TILE_PX; ++tx) bounds = max(bounds, tiles[tile_element(ivec2(tx, ty))].yz);
  return bounds;
}

// tile_bounds_over this invocation's pixels, then the largest over its subgroup: one value every
// lane shares (lavapipe runs 8 lanes in SIMD, a GPU warp 32), so loops bounded by it run in step and
// branches on it are uniform. Call it in uniform control flow, before any invocation returns; it
// bounds every lane's own needs, whatever the subgroup's shape.
ivec2 subgroup_tile_bounds(ivec2 lo, ivec2 hi) { return subgroupMax(tile_bounds_over(lo, hi)); }
#endif
