#include "coc_tiles.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "ceil_div.hpp"

namespace bokeh {

int gap_samples(int d, int tile_px, int spacing_px) {
  if (d == 0) return 0;
  const int gap_px = (std::abs(d) - 1) * tile_px + 1;
  return ceil_div(gap_px, spacing_px);
}

int CocTiles::reach_over(int x0, int y0, int x1, int y1) const {
  int d = -1;
  for (int ty = y0 / tile_px; ty <= y1 / tile_px; ++ty)
    for (int tx = x0 / tile_px; tx <= x1 / tile_px; ++tx)
      d = std::max(d, reach_index[static_cast<std::size_t>(ty) * tiles_x + tx]);
  return d;
}

int tile_reach_range(const GatherPattern& p, int tile_px) { return ceil_div(p.half() * p.spacing_px, tile_px); }

bool tile_reaches(int m, int dtx, int dty, int tile_px, const GatherPattern& p) {
  const int gi = gap_samples(dtx, tile_px, p.spacing_px), gj = gap_samples(dty, tile_px, p.spacing_px);
  return gi <= p.half() && gj <= p.half() && gi * gi + gj * gj <= m;
}

CocTiles coc_tiles(const Image& packed, const GatherPattern& p, int tile_px) {
  if (tile_px < 1) throw std::invalid_argument("coc_tiles: tile size must be >= 1 px, got " + std::to_string(tile_px));
  if (packed.channels != 4) throw std::invalid_argument("coc_tiles: expects the packed RGBA input (radius in alpha)");
  CocTiles t;
  t.tile_px = tile_px;
  t.tiles_x = ceil_div(packed.width, tile_px);
  t.tiles_y = ceil_div(packed.height, tile_px);
  const std::size_t count = static_cast<std::size_t>(t.tiles_x) * t.tiles_y;
  t.max_index.assign(count, 0);
  t.reach_index.assign(count, 0);
  const int cap = 2 * p.half() * p.half();
  for (int y = 0; y < packed.height; ++y)
    for (int x = 0; x < packed.width; ++x) {
      const float r = packed.px(x, y)[3];
      int& m = t.max_index[static_cast<std::size_t>(t.tile_of(x, y))];
      m = std::max(m, disc_index(r * r, p.spacing_px, cap));
    }
  const int range = tile_reach_range(p, tile_px);
  for (int ty = 0; ty < t.tiles_y; ++ty)
    for (int tx = 0; tx < t.tiles_x; ++tx) {
      int d = 0;
      for (int sy = std::max(0, ty - range); sy <= std::min(t.tiles_y - 1, ty + range); ++sy)
        for (int sx = std::max(0, tx - range); sx <= std::min(t.tiles_x - 1, tx + range); ++sx) {
          const int m = t.max_index[static_cast<std::size_t>(sy) * t.tiles_x + sx];
          if (m > d && tile_reaches(m, sx - tx, sy - ty, tile_px, p)) d = m;
        }
      t.reach_index[static_cast<std::size_t>(ty) * t.tiles_x + tx] = d;
    }
  t.scene_max_index = count ? *std::max_element(t.max_index.begin(), t.max_index.end()) : 0;
  return t;
}

}  // namespace bokeh
