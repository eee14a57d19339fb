#version 450
// Tile-max CoC map, pass 2 (kernels/core/coc_tiles.hpp): per tile, D = the largest M of the tiles
// that can reach it: gi = ceil(gx / k), gj = ceil(gy / k) from the pixel gaps between the tiles,
// gi, gj <= n and gi^2 + gj^2 <= M. Also the scene's largest M into element 0 (atomicMax).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int SPACING = 1;
#define TILE_PX_ID 1
#define TILES_BINDING 0
#define TILES_ACCESS
#include "tiles.glsl"

void main() {
  const ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  if (t.x >= tiles_x() || t.y >= tiles_y()) return;
  const int n = params.half_n, k = SPACING;
  const int range = (n * k + TILE_PX - 1) / TILE_PX;
  int d = 0;
  for (int sy = max(0, t.y - range); sy <= min(tiles_y() - 1, t.y + range); ++sy) {
    const int gj = gap_samples(sy - t.y, k);
    if (gj > n) continue;
    for (int sx = max(0, t.x - range); sx <= min(tiles_x() - 1, t.x + range); ++sx) {
      const int gi = gap_samples(sx - t.x, k);
      const int m = tiles[tile_element(ivec2(sx, sy))].x;
      if (gi <= n && gi * gi + gj * gj <= m) d = max(d, m);
    }
  }
  tiles[tile_element(t)].y = d;
  atomicMax(tiles[0].x, tiles[tile_element(t)].x);
}
