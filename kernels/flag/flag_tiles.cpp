#include "flag_tiles.hpp"

#include <algorithm>
#include <cstdint>

#include "ceil_div.hpp"

namespace bokeh {

std::vector<int> flag_write_layers(const CocTiles& t, int spacing_px, int half_n) {
  std::vector<int> z(t.reach_index.size(), -1);
  const int range = ceil_div(half_n * spacing_px, t.tile_px);
  for (int ty = 0; ty < t.tiles_y; ++ty)
    for (int tx = 0; tx < t.tiles_x; ++tx) {
      int& out = z[static_cast<std::size_t>(ty) * t.tiles_x + tx];
      for (int ry = std::max(0, ty - range); ry <= std::min(t.tiles_y - 1, ty + range); ++ry) {
        const int d = t.reach_index[static_cast<std::size_t>(ry) * t.tiles_x + tx];
        if (d <= 0) continue;  // that tile's output is its input: it reads no layer
        const int layer = static_cast<int>(std::min<std::int64_t>(isqrt(d), half_n));
        if (gap_samples(ry - ty, t.tile_px, spacing_px) <= layer) out = std::max(out, layer);
      }
    }
  return z;
}

GatherPattern scene_sized_pattern(const GatherPattern& p, int scene_max_index) {
  const int n = static_cast<int>(std::min<std::int64_t>(isqrt(std::max(scene_max_index, 0)), p.half()));
  return {2 * n + 1, p.spacing_px};
}

}  // namespace bokeh
