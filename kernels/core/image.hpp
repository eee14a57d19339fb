#pragma once
// A row-major, channel-interleaved float image: the one pixel container every stage shares.
#include <cstddef>
#include <vector>

namespace bokeh {

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;

  Image() = default;
  Image(int width_px, int height_px, int channel_count, float fill = 0.0f)
      : width(width_px), height(height_px), channels(channel_count),
        pixels(static_cast<std::size_t>(width_px) * height_px * channel_count, fill) {}

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * height; }
  float* px(int x, int y) { return pixels.data() + (static_cast<std::size_t>(y) * width + x) * channels; }
  const float* px(int x, int y) const {
    return pixels.data() + (static_cast<std::size_t>(y) * width + x) * channels;
  }
  bool same_shape(const Image& o) const {
    return width == o.width && height == o.height && channels == o.channels;
  }
};

}  // namespace bokeh
