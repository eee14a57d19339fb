#include "naive_gather.hpp"

#include <algorithm>
#include <vector>

#include "scratch.hpp"
#include "simd.hpp"

namespace bokeh {

Image naive_gather_reference(const Image& packed, const GatherPattern& p, int threads) {
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

// Eight adjacent outputs at a time. The input is split into planes (r, g, b, radius^2) padded by a
// block's width on both sides, radius^2 = -1 there (inside no disc), so a block's window of eight
// samples is one or two vector loads whether or not it overhangs the image. A sample outside the
// disc adds +0.0 (simd::masked), which leaves the sum exactly as it is: each output adds the same
// values in the same order as naive_gather_reference. Samples outside the image's largest disc are
// skipped (in_disc is monotonic in the radius, so no smaller disc holds them).
Image naive_gather(const Image& packed, const GatherPattern& p, int threads, const CocTiles* tiles) {
  using namespace simd;
  constexpr int kLanes = 8, kVectors = kLanes / kWidth, kPad = kLanes;
  const int w = packed.width, h = packed.height, n = p.half(), k = p.spacing_px;
  const std::size_t pw = static_cast<std::size_t>(w) + 2 * kPad + kLanes;  // + room for the last partial block
  const std::size_t plane = pw * static_cast<std::size_t>(h);
  Scratch<float> planes(4 * plane);
  float* const r_plane = planes.data();
  float* const g_plane = r_plane + plane;
  float* const b_plane = g_plane + plane;
  float* const r2_plane = b_plane + plane;
  std::vector<float> row_max_r2(static_cast<std::size_t>(h), 0.0f);
  parallel_rows(h, threads, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * pw;
    std::fill(r_plane + row, r_plane + row + pw, 0.0f);
    std::fill(g_plane + row, g_plane + row + pw, 0.0f);
    std::fill(b_plane + row, b_plane + row + pw, 0.0f);
    std::fill(r2_plane + row, r2_plane + row + pw, -1.0f);
    float max_r2 = 0.0f;
    for (int x = 0; x < w; ++x) {
      const float* s = packed.px(x, y);
      const std::size_t i = row + kPad + static_cast<std::size_t>(x);
      r_plane[i] = s[0], g_plane[i] = s[1], b_plane[i] = s[2];
      r2_plane[i] = s[3] * s[3];
      if (r2_plane[i] > max_r2) max_r2 = r2_plane[i];  // NaN radii add nothing: not counted
    }
    row_max_r2[static_cast<std::size_t>(y)] = max_r2;
  });
  const float max_r2 = h > 0 ? *std::max_element(row_max_r2.begin(), row_max_r2.end()) : 0.0f;
  const int max_index = disc_index(max_r2, k, 2 * n * n);

  Image out(w, h, 3);
  parallel_rows(h, threads, [&](int y) {
    for (int x0 = 0; x0 < w; x0 += kLanes) {
      f32v sum_r[kVectors] = {}, sum_g[kVectors] = {}, sum_b[kVectors] = {};
      const int bound = tiles ? tiles->reach_over(x0, y, std::min(w, x0 + kLanes) - 1, y) : max_index;
      for (int j = -n; j <= n; ++j) {
        const int sy = y + j * k;
        if (sy < 0 || sy >= h) continue;
        const int reach = reach_layer(bound, j, n);
        // Columns whose window of eight samples overlaps the image.
        const int i_lo = std::max(-reach, -((x0 + kLanes - 1) / k)), i_hi = std::min(reach, (w - 1 - x0) / k);
        const std::size_t base = static_cast<std::size_t>(sy) * pw + kPad + static_cast<std::size_t>(x0);
        for (int i = i_lo; i <= i_hi; ++i) {
          // The disc test of in_disc, lane by lane.
          const f32v d = splat(static_cast<float>(i * k * i * k + j * k * j * k));
          for (int v = 0; v < kVectors; ++v) {
            const std::size_t at = base + static_cast<std::ptrdiff_t>(i * k) + static_cast<std::size_t>(v * kWidth);
            const i32v inside = d <= load(r2_plane + at);
            sum_r[v] += masked(load(r_plane + at), inside);
            sum_g[v] += masked(load(g_plane + at), inside);
            sum_b[v] += masked(load(b_plane + at), inside);
          }
        }
      }
      for (int l = 0; l < kLanes && x0 + l < w; ++l) {
        float* o = out.px(x0 + l, y);
        o[0] = sum_r[l / kWidth][l % kWidth], o[1] = sum_g[l / kWidth][l % kWidth], o[2] = sum_b[l / kWidth][l % kWidth];
      }
    }
  });
  return out;
}

}  // namespace bokeh
