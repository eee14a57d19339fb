#include "gaussian.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bokeh {

std::vector<float> gaussian_taps(int radius_px) {
  if (radius_px < 1) throw std::invalid_argument("gaussian: the largest CoC radius must be >= 1 px");
  const double sigma = radius_px / 2.0;
  std::vector<double> w;
  double sum = 0;
  for (int i = -radius_px; i <= radius_px; ++i) sum += w.emplace_back(std::exp(-0.5 * i * i / (sigma * sigma)));
  std::vector<float> taps;
  for (double v : w) taps.push_back(static_cast<float>(v / sum));
  return taps;
}

Image gaussian_blur(const Image& color, const Image& radius_px, int max_radius_px, int threads) {
  if (color.channels < 3 || radius_px.channels != 1 || color.width != radius_px.width ||
      color.height != radius_px.height)
    throw std::invalid_argument("gaussian: colour (>= 3 channels) and radius (1 channel) must match in size");
  const std::vector<float> taps = gaussian_taps(max_radius_px);
  const int r = max_radius_px, w = color.width, h = color.height;
  // The same float operations in the same order as shaders/gaussian/*.comp.
  Image blurred(w, h, 3);
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float sum[3] = {0, 0, 0};
      for (int i = -r; i <= r; ++i) {
        const float* c = color.px(std::clamp(x + i, 0, w - 1), y);
        for (int ch = 0; ch < 3; ++ch) sum[ch] += taps[i + r] * c[ch];
      }
      std::copy(sum, sum + 3, blurred.px(x, y));
    }
  });
  Image out(w, h, 3);
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float sum[3] = {0, 0, 0};
      for (int i = -r; i <= r; ++i) {
        const float* b = blurred.px(x, std::clamp(y + i, 0, h - 1));
        for (int ch = 0; ch < 3; ++ch) sum[ch] += taps[i + r] * b[ch];
      }
      const float a = std::clamp(*radius_px.px(x, y) / static_cast<float>(r), 0.0f, 1.0f);
      for (int ch = 0; ch < 3; ++ch) out.px(x, y)[ch] = color.px(x, y)[ch] * (1.0f - a) + sum[ch] * a;
    }
  });
  return out;
}

}  // namespace bokeh
