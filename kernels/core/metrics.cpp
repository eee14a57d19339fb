#include "metrics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "image_io.hpp"

namespace bokeh {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double luminance(const float* rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

std::vector<double> luminance_plane(const Image& image) {
  std::vector<double> y(image.pixel_count());
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = luminance(image.pixels.data() + i * image.channels);
  return y;
}

void check_comparable(const Image& result, const Image& reference, const char* what) {
  if (!result.same_shape(reference))
    throw std::invalid_argument(fmt::format("{}: result is {}x{}x{} but reference is {}x{}x{}", what, result.width,
                                            result.height, result.channels, reference.width, reference.height,
                                            reference.channels));
  if (reference.channels < 3)
    throw std::invalid_argument(fmt::format("{}: images need RGB, got {} channel(s)", what, reference.channels));
}

// Mean SSIM over all valid windows of two [0,1] planes (see metrics.hpp for the exact definition).
double mean_ssim(const std::vector<double>& a, const std::vector<double>& b, int w, int h) {
  constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03, kSigma = 1.5;
  const int radius = std::min(5, (std::min(w, h) - 1) / 2);
  std::vector<double> g(2 * radius + 1);
  for (int i = -radius; i <= radius; ++i) g[i + radius] = std::exp(-0.5 * i * i / (kSigma * kSigma));
  const double g_sum = std::accumulate(g.begin(), g.end(), 0.0);
  for (double& v : g) v /= g_sum;

  // Separable filtering of the five moments: horizontal pass over valid columns, then vertical.
  const int vw = w - 2 * radius, vh = h - 2 * radius;
  std::array<std::vector<double>, 5> horizontal;
  for (auto& m : horizontal) m.assign(static_cast<std::size_t>(h) * vw, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < vw; ++x)
      for (int i = 0; i <= 2 * radius; ++i) {
        const std::size_t src = static_cast<std::size_t>(y) * w + x + i, dst = static_cast<std::size_t>(y) * vw + x;
        const double wa = a[src], wb = b[src];
        horizontal[0][dst] += g[i] * wa;
        horizontal[1][dst] += g[i] * wb;
        horizontal[2][dst] += g[i] * wa * wa;
        horizontal[3][dst] += g[i] * wb * wb;
        horizontal[4][dst] += g[i] * wa * wb;
      }
  double ssim_sum = 0.0;
  for (int y = 0; y < vh; ++y)
    for (int x = 0; x < vw; ++x) {
      double m[5] = {0, 0, 0, 0, 0};
      for (int j = 0; j <= 2 * radius; ++j)
        for (int k = 0; k < 5; ++k) m[k] += g[j] * horizontal[k][static_cast<std::size_t>(y + j) * vw + x];
      const double mu_a = m[0], mu_b = m[1];
      const double var_a = m[2] - mu_a * mu_a, var_b = m[3] - mu_b * mu_b, cov = m[4] - mu_a * mu_b;
      ssim_sum += ((2 * mu_a * mu_b + kC1) * (2 * cov + kC2)) /
                  ((mu_a * mu_a + mu_b * mu_b + kC1) * (var_a + var_b + kC2));
    }
  return ssim_sum / (static_cast<double>(vw) * vh);
}

// Viridis (matplotlib's perceptually uniform map) at nine even stops, sRGB-encoded.
std::array<float, 3> viridis(double t) {
  static constexpr std::array<std::array<float, 3>, 9> kStops = {{
      {0x44 / 255.f, 0x01 / 255.f, 0x54 / 255.f}, {0x47 / 255.f, 0x2c / 255.f, 0x7a / 255.f},
      {0x3b / 255.f, 0x51 / 255.f, 0x8b / 255.f}, {0x2c / 255.f, 0x71 / 255.f, 0x8e / 255.f},
      {0x21 / 255.f, 0x90 / 255.f, 0x8d / 255.f}, {0x27 / 255.f, 0xad / 255.f, 0x81 / 255.f},
      {0x5c / 255.f, 0xc8 / 255.f, 0x63 / 255.f}, {0xaa / 255.f, 0xdc / 255.f, 0x32 / 255.f},
      {0xfd / 255.f, 0xe7 / 255.f, 0x25 / 255.f},
  }};
  const double s = std::clamp(t, 0.0, 1.0) * (kStops.size() - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(s), kStops.size() - 2);
  const float f = static_cast<float>(s - i);
  std::array<float, 3> c;
  for (int k = 0; k < 3; ++k) c[k] = kStops[i][k] + f * (kStops[i + 1][k] - kStops[i][k]);
  return c;
}

}  // namespace

ErrorMetrics compare_images(const Image& result, const Image& reference) {
  check_comparable(result, reference, "compare_images");
  const int channels = reference.channels;
  double squared = 0.0, max_abs = 0.0, sum_result = 0.0, sum_reference = 0.0;
  float peak = -std::numeric_limits<float>::infinity();
  for (std::size_t p = 0; p < reference.pixel_count(); ++p)
    for (int k = 0; k < 3; ++k) {
      const double a = result.pixels[p * channels + k], b = reference.pixels[p * channels + k];
      squared += (a - b) * (a - b);
      max_abs = std::max(max_abs, std::abs(a - b));
      sum_result += a;
      sum_reference += b;
      peak = std::max(peak, reference.pixels[p * channels + k]);
    }
  ErrorMetrics m;
  const double n = 3.0 * static_cast<double>(reference.pixel_count());
  m.rmse = n > 0 ? std::sqrt(squared / n) : 0.0;
  m.psnr_db = m.rmse == 0.0 ? kInf : 20.0 * std::log10((peak > 0.0f ? peak : 1.0) / m.rmse);
  m.max_abs_error = max_abs;
  const double energy_gap = std::abs(sum_result - sum_reference);
  m.mean_relative_energy_error =
      energy_gap == 0.0 ? 0.0 : (sum_reference == 0.0 ? kInf : energy_gap / std::abs(sum_reference));
  m.ssim = n > 0 ? mean_ssim(luminance_plane(tone_map_for_display(result)),
                             luminance_plane(tone_map_for_display(reference)), reference.width, reference.height)
                 : 1.0;
  return m;
}

ErrorMetrics compare_interior(const Image& result, const Image& reference, int margin_px) {
  check_comparable(result, reference, "compare_interior");
  const int m = std::max(margin_px, 0), w = reference.width - 2 * m, h = reference.height - 2 * m;
  if (w <= 0 || h <= 0) {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    return {kNaN, kNaN, kNaN, kNaN, kNaN};
  }
  auto crop = [&](const Image& image) {
    Image inner(w, h, image.channels);
    for (int y = 0; y < h; ++y)
      std::copy_n(image.px(m, y + m), static_cast<std::size_t>(w) * image.channels, inner.px(0, y));
    return inner;
  };
  return compare_images(crop(result), crop(reference));
}

Image to_display_srgb(const Image& linear) {
  Image display = tone_map_for_display(linear);
  for (float& v : display.pixels) v = static_cast<float>(encode_srgb(v));
  return display;
}

Image error_heat_map(const Image& result, const Image& reference) {
  check_comparable(result, reference, "error_heat_map");
  const std::vector<double> a = luminance_plane(result), b = luminance_plane(reference);
  std::vector<double> error(a.size());
  for (std::size_t i = 0; i < error.size(); ++i) error[i] = std::abs(a[i] - b[i]);
  double scale = 0.0;
  if (!error.empty()) {
    std::vector<double> sorted = error;
    auto p99 = sorted.begin() + static_cast<std::ptrdiff_t>(0.99 * (sorted.size() - 1));
    std::nth_element(sorted.begin(), p99, sorted.end());
    scale = *p99 > 0.0 ? *p99 : *std::max_element(error.begin(), error.end());
  }
  Image map(reference.width, reference.height, 3);
  for (std::size_t i = 0; i < error.size(); ++i) {
    const auto c = viridis(scale > 0.0 ? error[i] / scale : 0.0);
    std::copy(c.begin(), c.end(), map.pixels.begin() + static_cast<std::ptrdiff_t>(3 * i));
  }
  return map;
}

Image contact_sheet(const std::vector<std::pair<std::string, Image>>& panels) {
  constexpr int kGap = 8, kLabelHeight = 20, kFontSize = 14;
  constexpr float kBackground = 0.12f;
  if (panels.empty()) throw std::invalid_argument("contact_sheet: no panels");
  int width = kGap, panel_height = 0;
  bool labelled = false;
  for (const auto& [label, image] : panels) {
    if (image.channels != 1 && image.channels != 3)
      throw std::invalid_argument(
          fmt::format("contact_sheet: panel '{}' has {} channels, need 1 or 3", label, image.channels));
    width += image.width + kGap;
    panel_height = std::max(panel_height, image.height);
    labelled = labelled || !label.empty();
  }
  const int top = kGap + (labelled ? kLabelHeight : 0);
  Image sheet(width, top + panel_height + kGap, 3, kBackground);
  int left = kGap;
  for (const auto& [label, image] : panels) {
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        for (int k = 0; k < 3; ++k) sheet.px(left + x, top + y)[k] = image.px(x, y)[image.channels == 3 ? k : 0];
    // Without a font, or with the lean image back-end (no text renderer), the strip stays blank: the
    // panels keep their order (documented in metrics.hpp and the README).
    if (!label.empty()) draw_text(sheet, left, top - 6, label, kFontSize, {0.92f, 0.92f, 0.92f});
    left += image.width + kGap;
  }
  return sheet;
}

}  // namespace bokeh
