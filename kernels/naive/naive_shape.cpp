#include "naive_shape.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bokeh {

ShapeLattice::ShapeLattice(const Aperture& aperture, const GatherPattern& p) : side(2 * p.half() + 1) {
  const int n = p.half(), k = p.spacing_px;
  for (int j = -n; j <= n; ++j)
    for (int i = -n; i <= n; ++i) {
      float g = static_cast<float>(aperture.gauge(i * k, j * k));
      // gauge >= |offset| in exact arithmetic: only rounding can leave g under the disc's test.
      while (!in_disc(g * g, i * k, j * k)) g = std::nextafter(g, std::numeric_limits<float>::infinity());
      gauge.push_back(g);
    }
  sorted = gauge;
  std::sort(sorted.begin(), sorted.end());
}

int ShapeLattice::area(float radius_px) const {
  return static_cast<int>(std::upper_bound(sorted.begin(), sorted.end(), radius_px) - sorted.begin());
}

Image naive_shape_gather(const Image& color, const Image& radius_px, const ShapeLattice& lattice,
                         const GatherPattern& p, int threads, const CocTiles* tiles) {
  const int w = color.width, h = color.height, n = p.half(), k = p.spacing_px;
  // Each source's weight once: colour / its shape's area on the pattern (what the GPU's pack pass writes).
  Image weighted(w, h, 4);
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float r = *radius_px.px(x, y), area = static_cast<float>(lattice.area(r));
      float* o = weighted.px(x, y);
      for (int c = 0; c < 3; ++c) o[c] = color.px(x, y)[c] / area;
      o[3] = r;
    }
  });
  Image out(w, h, 3);
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float sum[3] = {0, 0, 0};
      // Adaptive: rows and columns inside the disc of index D (-1: none), else the whole pattern.
      const int bound = tiles ? tiles->reach_over(x, y, x, y) : 2 * n * n;
      for (int j = -n; j <= n; ++j) {
        const int sy = y + j * k, reach = reach_layer(bound, j, n);
        if (sy < 0 || sy >= h || reach < 0) continue;
        // The source's shape reaches this pixel when it covers the offset from the source to the pixel,
        // (-i k, -j k): the lattice's row -j, column -i (the shape need not be symmetric).
        const float* gauge_row = lattice.gauge.data() + static_cast<std::size_t>(n - j) * lattice.side + n;
        for (int i = -reach; i <= reach; ++i) {
          const int sx = x + i * k;
          if (sx < 0 || sx >= w) continue;
          const float* s = weighted.px(sx, sy);
          if (gauge_row[-i] <= s[3])
            for (int c = 0; c < 3; ++c) sum[c] += s[c];
        }
      }
      float* o = out.px(x, y);
      for (int c = 0; c < 3; ++c) o[c] = sum[c];
    }
  });
  return out;
}

}  // namespace bokeh
