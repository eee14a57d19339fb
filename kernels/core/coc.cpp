#include "coc.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace bokeh {

void check_color(const Image& color) {
  if (color.channels < 3) throw std::invalid_argument("colour needs at least three channels");
  for (int y = 0; y < color.height; ++y)
    for (int x = 0; x < color.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = color.px(x, y)[c];
        if (!std::isfinite(v))
          throw std::invalid_argument(fmt::format(
              "colour at pixel ({}, {}) channel {} is {}: colours must be finite (a NaN or Inf would spread over "
              "its whole disc)",
              x, y, "RGB"[c], v));
      }
}

void check_depth(const Image& depth_m) {
  if (depth_m.channels != 1) throw std::invalid_argument("depth must have exactly one channel");
  for (int y = 0; y < depth_m.height; ++y)
    for (int x = 0; x < depth_m.width; ++x) {
      const float d = *depth_m.px(x, y);
      if (!std::isfinite(d) || d <= 0.0f)
        throw std::invalid_argument(
            fmt::format("depth at pixel ({}, {}) is {}: depths must be finite and > 0 metres", x, y, d));
    }
}

Image coc_radius_image(const Image& depth_m, const Lens& lens, float max_radius_px) {
  validate(lens);
  check_depth(depth_m);
  const float scale = static_cast<float>(coc_scale_px(lens, depth_m.width));
  const float focus = static_cast<float>(lens.focus_distance_m);
  Image radius(depth_m.width, depth_m.height, 1);
  for (std::size_t i = 0; i < depth_m.pixels.size(); ++i) {
    const float d = depth_m.pixels[i];
    // Same float expression as shaders/common/coc.comp, so both sides clamp the same radii.
    radius.pixels[i] = std::min(scale * std::abs(d - focus) / d, max_radius_px);
  }
  return radius;
}

Image pack_gather_input(const Image& color, const Image& radius_px, const GatherPattern& pattern, int threads) {
  if (color.channels < 3) throw std::invalid_argument("colour needs at least three channels");
  if (color.width != radius_px.width || color.height != radius_px.height)
    throw std::invalid_argument("colour and CoC images differ in size");
  const DiscAreaTable areas(pattern);
  Image packed(color.width, color.height, 4);
  parallel_rows(color.height, threads, [&](int y) {
    for (int x = 0; x < color.width; ++x) {
      const float r = *radius_px.px(x, y);
      const float inv_area = 1.0f / static_cast<float>(areas.area(r));
      float* out = packed.px(x, y);
      for (int c = 0; c < 3; ++c) out[c] = color.px(x, y)[c] * inv_area;
      out[3] = r;
    }
  });
  return packed;
}

double max_defocus_ratio(const Image& depth_m, const Lens& lens) {
  double ratio = 0.0;
  for (float d : depth_m.pixels) ratio = std::max(ratio, std::abs(d - lens.focus_distance_m) / d);
  return ratio;
}

Lens with_max_coc_radius(Lens lens, const Image& depth_m, double radius_px) {
  if (!std::isfinite(radius_px) || radius_px < 0.0)
    throw std::invalid_argument(fmt::format("the largest CoC radius to fit must be finite and >= 0 px, got {}", radius_px));
  const double ratio = max_defocus_ratio(depth_m, lens);
  if (ratio <= 0.0 || radius_px <= 0.0) {
    lens.f_stop = 1e9;  // everything in focus or no blur wanted: a pinhole
    return lens;
  }
  // coc_scale_px is proportional to 1 / f_stop.
  const double scale_now = coc_scale_px(lens, depth_m.width);
  lens.f_stop *= scale_now * ratio / radius_px;
  return lens;
}

}  // namespace bokeh
