#include "flag_reduced.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "ceil_div.hpp"
#include "coc.hpp"

namespace bokeh {

const std::vector<int>& flag_buffer_scales() {
  static const std::vector<int> scales = {1, 2, 4};
  return scales;
}

void check_buffer_scale(int scale) {
  const auto& scales = flag_buffer_scales();
  if (std::find(scales.begin(), scales.end(), scale) == scales.end())
    throw std::invalid_argument(fmt::format("buffer scale must be one of {} (the 3D buffer at 1/scale resolution), got {}",
                                            fmt::join(scales, ", "), scale));
}

GatherPattern reduced_pattern(const GatherPattern& full, int scale) {
  check_buffer_scale(scale);
  validate(full);
  return {2 * ceil_div(full.layers(), scale) - 1, full.spacing_px};
}

Image flag_downsample(const Image& color, const Image& radius_px, const GatherPattern& low, int scale) {
  check_buffer_scale(scale);
  if (color.channels < 3 || radius_px.channels != 1 || color.width != radius_px.width ||
      color.height != radius_px.height)
    throw std::invalid_argument("flag_downsample: colour (>= 3 channels) and radius (1 channel) must match in size");
  const int w = ceil_div(color.width, scale), h = ceil_div(color.height, scale);
  const DiscAreaTable areas(low);
  Image packed(w, h, 4);
  for (int ly = 0; ly < h; ++ly)
    for (int lx = 0; lx < w; ++lx) {
      // Same order and float operations as shaders/flag/downsample.comp.
      float sum[3] = {0, 0, 0}, weight = 0, weighted_radius = 0;
      int count = 0;
      for (int y = ly * scale; y < std::min(color.height, ly * scale + scale); ++y)
        for (int x = lx * scale; x < std::min(color.width, lx * scale + scale); ++x) {
          const float r = *radius_px.px(x, y), wi = low_res_weight(r, scale);
          for (int c = 0; c < 3; ++c) sum[c] += wi * color.px(x, y)[c];
          weight += wi;
          weighted_radius += wi * r;
          ++count;
        }
      const float mean_radius = weight > 0.0f ? weighted_radius / weight : 0.0f;
      const float r = std::min(mean_radius / static_cast<float>(scale), low.max_radius_px());
      const float inv = 1.0f / (static_cast<float>(count) * static_cast<float>(areas.area(r)));
      float* out = packed.px(lx, ly);
      for (int c = 0; c < 3; ++c) out[c] = sum[c] * inv;
      out[3] = r;
    }
  return packed;
}

Image flag_upsample(const Image& blurred_low, const Image& color, const Image& radius_px, int scale) {
  check_buffer_scale(scale);
  const int lw = blurred_low.width, lh = blurred_low.height;
  if (lw != ceil_div(color.width, scale) || lh != ceil_div(color.height, scale))
    throw std::invalid_argument("flag_upsample: low-res image is not the colour's size / scale");
  Image out(color.width, color.height, 3);
  const float inv_scale = 1.0f / static_cast<float>(scale);  // exact for 1, 2, 4
  for (int y = 0; y < color.height; ++y)
    for (int x = 0; x < color.width; ++x) {
      // Same float operations as shaders/flag/upsample.comp.
      const float u = (static_cast<float>(x) + 0.5f) * inv_scale - 0.5f;
      const float v = (static_cast<float>(y) + 0.5f) * inv_scale - 0.5f;
      const float fu = std::floor(u), fv = std::floor(v);
      const float ax = u - fu, ay = v - fv;
      const int x0 = std::clamp(static_cast<int>(fu), 0, lw - 1), x1 = std::clamp(static_cast<int>(fu) + 1, 0, lw - 1);
      const int y0 = std::clamp(static_cast<int>(fv), 0, lh - 1), y1 = std::clamp(static_cast<int>(fv) + 1, 0, lh - 1);
      const float sharp = 1.0f - low_res_weight(*radius_px.px(x, y), scale);
      float* o = out.px(x, y);
      for (int c = 0; c < 3; ++c) {
        const float top = blurred_low.px(x0, y0)[c] * (1.0f - ax) + blurred_low.px(x1, y0)[c] * ax;
        const float bottom = blurred_low.px(x0, y1)[c] * (1.0f - ax) + blurred_low.px(x1, y1)[c] * ax;
        const float b = top * (1.0f - ay) + bottom * ay;
        o[c] = sharp * color.px(x, y)[c] + b;
      }
    }
  return out;
}

ReducedFlag flag_reduced(const Image& color, const Image& radius_px, const GatherPattern& pattern, int scale,
                         LayerPrecision precision, int threads) {
  check_buffer_scale(scale);
  validate(pattern);
  check_layer_input(color, precision);  // before the downsample, whose weights could hide a negative colour
  ReducedFlag r;
  r.pattern = reduced_pattern(pattern, scale);
  r.packed = scale == 1 ? pack_gather_input(color, radius_px, pattern, threads)
                        : flag_downsample(color, radius_px, r.pattern, scale);
  r.layers = flag_horizontal(r.packed, r.pattern, precision, threads);
  r.blurred = flag_vertical(r.layers, r.pattern, threads);
  r.output = scale == 1 ? r.blurred : flag_upsample(r.blurred, color, radius_px, scale);
  return r;
}

Image flag_reduced_blur(const Image& color, const Image& radius_px, const GatherPattern& pattern, int scale,
                        LayerPrecision precision, int threads) {
  // flag_reduced's passes without keeping the intermediates; flag_blur gives flag_vertical(flag_horizontal()).
  check_buffer_scale(scale);
  validate(pattern);
  if (scale == 1) return flag_blur(pack_gather_input(color, radius_px, pattern, threads), pattern, precision, threads);
  check_layer_input(color, precision);
  const GatherPattern low = reduced_pattern(pattern, scale);
  const Image blurred = flag_blur(flag_downsample(color, radius_px, low, scale), low, precision, threads);
  return flag_upsample(blurred, color, radius_px, scale);
}

}  // namespace bokeh
