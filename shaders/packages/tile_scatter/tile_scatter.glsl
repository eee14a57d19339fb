// Shared by the tile_scatter passes (include after common.glsl): the tile grid over the frame.
// TILE_PX (specialisation constant 1) is the manifest's option tile_px: 8, 16 or 32 px squares, a
// multiple of the gather's OUTPUTS = 4, so the 4 adjacent pixels one gather invocation computes
// always share one tile. Tile t (row-major) is element t of the rg32f buffers `tiles` (binding 5)
// and `tiles_dilated` (binding 6): .x the largest |signed CoC| in px, .y the nearest (most negative)
// signed CoC in px.
layout(constant_id = 1) const int TILE_PX = 16;

int tiles_x() { return (params.width_px + TILE_PX - 1) / TILE_PX; }
int tiles_y() { return (params.height_px + TILE_PX - 1) / TILE_PX; }
ivec2 tile_grid() { return ivec2(tiles_x(), tiles_y()); }
uint tile_index(ivec2 tile) { return uint(tile.y * tiles_x() + tile.x); }
