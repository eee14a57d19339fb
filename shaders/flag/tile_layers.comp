#version 450
// FLAG's layer write bound (kernels/core/coc_tiles.hpp, flag_write_layers): per tile, Z = the largest
// layer min(isqrt(D_T), n) of the tiles T of its tile column with D_T > 0 whose vertical pass reads
// its rows (ceil(row gap / k) <= that layer); -1 if none. n: params.half_n, the highest layer allocated.
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
  int z = -1;
  for (int ry = max(0, t.y - range); ry <= min(tiles_y() - 1, t.y + range); ++ry) {
    const int d = tiles[tile_element(ivec2(t.x, ry))].y;
    if (d <= 0) continue;  // that tile's output is its input: it reads no layer
    const int layer = min(isqrt(d), n);
    if (gap_samples(ry - t.y, k) <= layer) z = max(z, layer);
  }
  tiles[tile_element(t)].z = z;
}
