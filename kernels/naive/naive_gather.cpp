#include "naive_gather.hpp"

namespace bokeh {

Image naive_gather(const Image& packed, const GatherPattern& p, int threads) {
  Image out(packed.width, packed.height, 3);
  const int n = p.half(), k = p.spacing_px;
  parallel_rows(packed.height, threads, [&](int y) {
    for (int x = 0; x < packed.width; ++x) {
      float sum[3] = {0, 0, 0};
      for (int j = -n; j <= n; ++j) {
        const int sy = y + j * k;
        if (sy < 0 || sy >= packed.height) continue;
        for (int i = -n; i <= n; ++i) {
          const int sx = x + i * k;
          if (sx < 0 || sx >= packed.width) continue;
          const float* s = packed.px(sx, sy);
          if (!in_disc(s[3] * s[3], i * k, j * k)) continue;
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
