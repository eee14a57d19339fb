#pragma once
// Helpers several test files share: random images, frames with a given CoC, sums, bit-for-bit and
// numeric differences, disc radius, and the error propagation of the circular filters' vertical pass.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "image.hpp"

namespace bokeh::test {

// Uniform in [lo, hi), reproducible for a seed.
inline Image random_image(int w, int h, int channels, float lo, float hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  Image img(w, h, channels);
  for (float& v : img.pixels) v = u(rng);
  return img;
}

// RGB uniform in [0, 4) inside a border of `margin` black pixels, reproducible for a seed: energy
// tests keep the light far enough from the edges that no blurred disc leaves the image.
inline Image random_image_in_black_border(int w, int h, int margin, unsigned seed) {
  Image img = random_image(w, h, 3, 0.0f, 4.0f, seed);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (x < margin || y < margin || x >= w - margin || y >= h - margin)
        for (int c = 0; c < 3; ++c) img.px(x, y)[c] = 0.0f;
  return img;
}

inline double channel_sum(const Image& image, int channel) {
  double s = 0.0;
  for (std::size_t p = 0; p < image.pixel_count(); ++p) s += image.pixels[p * image.channels + channel];
  return s;
}

inline double rgb_sum(const Image& image) { return channel_sum(image, 0) + channel_sum(image, 1) + channel_sum(image, 2); }

// The same floats bit for bit (so -0 differs from +0 and NaNs compare), naming the first difference.
inline ::testing::AssertionResult same_bits(const Image& a, const Image& b) {
  if (!a.same_shape(b)) return ::testing::AssertionFailure() << "shapes differ";
  for (std::size_t i = 0; i < a.pixels.size(); ++i)
    if (std::memcmp(&a.pixels[i], &b.pixels[i], sizeof(float)) != 0)
      return ::testing::AssertionFailure() << "value " << i << ": " << a.pixels[i] << " vs " << b.pixels[i];
  return ::testing::AssertionSuccess();
}

inline double max_abs_diff(const Image& a, const Image& b) {
  double m = 0.0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) m = std::max(m, std::abs(double(a.pixels[i]) - b.pixels[i]));
  return m;
}

constexpr float kFocusM = 3.0f;  // Lens{}'s focus distance

// A scene with its CoC given directly (not through a lens): depth decides near (in front of the
// focus) or far, radius_px the CoC.
struct Frame {
  Image color, depth_m, radius_px;
};

inline Frame black_frame(int w, int h, float depth_m, float radius_px) {
  return {Image(w, h, 3), Image(w, h, 1, depth_m), Image(w, h, 1, radius_px)};
}

// Radius where the output along the four axis directions first drops below half the plateau
// (mean over r <= disc / 2), linearly interpolated between pixels, averaged over the directions.
inline double half_plateau_radius(const Image& img, int channel, int cx, int cy, double disc_radius_px) {
  double plateau = 0.0;
  int count = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (std::hypot(x - cx, y - cy) <= disc_radius_px / 2) plateau += img.px(x, y)[channel], ++count;
  plateau /= count;
  double sum = 0.0;
  const int dirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const auto& d : dirs) {
    double prev = img.px(cx, cy)[channel];
    for (int i = 1;; ++i) {
      const double v = img.px(cx + i * d[0], cy + i * d[1])[channel];
      if (v < plateau / 2) {
        sum += (i - 1) + (prev - plateau / 2) / (prev - v);
        break;
      }
      prev = v;
    }
  }
  return sum / 4;
}

}  // namespace bokeh::test
