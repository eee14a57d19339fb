#include "spiral.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "signed_coc.hpp"

namespace bokeh {

namespace {

const double kGoldenAngle = std::numbers::pi * (3.0 - std::sqrt(5.0));  // 2.39996323 rad

// Walks Godot's loop, calling fn(angle, radius) per sample; returns the count.
template <class Fn>
std::int64_t walk_spiral(double spacing_px, double max_radius_px, Fn&& fn) {
  if (!(spacing_px > 0.0) || !std::isfinite(spacing_px) || !std::isfinite(max_radius_px))
    throw std::invalid_argument("spiral: the spacing must be finite and > 0 px");
  std::int64_t count = 0;
  double angle = 0.0;
  for (double radius = spacing_px; radius < max_radius_px; radius += spacing_px / radius) {
    fn(angle, radius);
    angle += kGoldenAngle;
    ++count;
  }
  return count;
}

}  // namespace

std::vector<SpiralSample> spiral_samples(double spacing_px, double max_radius_px) {
  std::vector<SpiralSample> samples;
  walk_spiral(spacing_px, max_radius_px, [&](double angle, double radius) {
    const double count = static_cast<double>(samples.size()) + 2.0;  // centre + samples so far + this one
    const SubpixelOffset o =
        split_offset(static_cast<float>(std::cos(angle) * radius), static_cast<float>(std::sin(angle) * radius));
    samples.push_back({static_cast<float>(o.x_px), static_cast<float>(o.y_px), o.fx, o.fy,
                       static_cast<float>(radius) - 0.5f, static_cast<float>(1.0 / count), {0.0f, 0.0f}});
  });
  return samples;
}

std::int64_t spiral_sample_count(double spacing_px, double max_radius_px) {
  return walk_spiral(spacing_px, max_radius_px, [](double, double) {});
}

Image spiral_blur(const Image& signed_coc, const std::vector<SpiralSample>& spiral, float clamp_factor, int threads) {
  if (signed_coc.channels != 4) throw std::invalid_argument("spiral: input must be RGBA (rgb, signed CoC)");
  const int w = signed_coc.width, h = signed_coc.height;
  Image out(w, h, 3);
  std::vector<SubpixelOffset> offsets;
  for (const SpiralSample& t : spiral)
    offsets.push_back({static_cast<int>(t.x_px), static_cast<int>(t.y_px), t.fx, t.fy});
  // The same float operations in the same order as shaders/spiral/spiral.comp.
  parallel_rows(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* centre = signed_coc.px(x, y);
      float avg[3] = {centre[0], centre[1], centre[2]};
      const float c = centre[3];
      const float background_limit = std::abs(c) * clamp_factor;
      for (std::size_t i = 0; i < spiral.size(); ++i) {
        const SpiralSample& t = spiral[i];
        const float* texel[4];
        bilinear_texels(signed_coc, x, y, offsets[i], texel);
        float s[4];
        bilinear_rgba(texel, offsets[i], s);
        float size = std::abs(s[3]);
        if (s[3] > c) size = std::min(size, background_limit);  // behind the pixel: clamp its CoC
        const float e = std::clamp(size - t.edge_start_px, 0.0f, 1.0f);
        const float m = e * e * (3.0f - 2.0f * e);  // smoothstep(r - 1/2, r + 1/2, size)
        // Off the image: no contribution (the running average goes on).
        const float weight = sample_inside(signed_coc, x, y, offsets[i]) ? m * t.inverse_count : 0.0f;
        for (int ch = 0; ch < 3; ++ch) avg[ch] = avg[ch] + (s[ch] - avg[ch]) * weight;
      }
      std::copy(avg, avg + 3, out.px(x, y));
    }
  });
  return out;
}

}  // namespace bokeh
