#pragma once
// What the engine-style gathers (spiral, hexagon) read: the colour with the CoC radius in alpha, signed
// as Godot's bokeh passes store it (near the focus plane's front negative, behind it positive), and
// its bilinear fetch (the engines sample a linearly filtered texture). GPU twins:
// shaders/common/signed_coc.comp and shaders/common/bilinear.glsl, with the same float operations in
// the same order (the shaders mark them `precise`, so no fused multiply-add), so both sides agree to
// the last bit on the same input.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "image.hpp"

namespace bokeh {

// RGBA = (rgb, -r where depth < focus, else +r); r from the shared CoC pass (radius_px).
inline Image signed_coc_image(const Image& color, const Image& radius_px, const Image& depth_m, float focus_m) {
  if (color.channels < 3 || radius_px.channels != 1 || depth_m.channels != 1 || color.width != radius_px.width ||
      color.height != radius_px.height || !depth_m.same_shape(radius_px))
    throw std::invalid_argument("signed CoC: colour (>= 3 channels), radius and depth (1 channel) must match in size");
  Image out(color.width, color.height, 4);
  for (std::size_t i = 0; i < out.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) out.pixels[i * 4 + c] = color.pixels[i * color.channels + c];
    const float r = radius_px.pixels[i];
    out.pixels[i * 4 + 3] = depth_m.pixels[i] < focus_m ? -r : r;
  }
  return out;
}

// A bilinear sample at (x, y) in pixel units (pixel centres at integers): the four nearest pixels
// (clamped to the image, which matters only on its last row and column, where the far weight is 0)
// and the fractions. `inside`: the point lies within the outermost pixel centres. The gathers skip
// samples that are not inside: light from beyond the image is absent, as in the exact reference (a
// texture sampler's clamp-to-edge would repeat the border pixels and smear them outwards-in). Mirrors
// bilinear_at() in shaders/common/bilinear.glsl.
struct BilinearTaps {
  const float* texel[4];  // (x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)
  float fx, fy;
  bool inside;
};

inline BilinearTaps bilinear_taps(const Image& img, float x, float y) {
  const float x0 = std::floor(x), y0 = std::floor(y);
  const int ix = static_cast<int>(x0), iy = static_cast<int>(y0);
  const int xa = std::clamp(ix, 0, img.width - 1), xb = std::clamp(ix + 1, 0, img.width - 1);
  const int ya = std::clamp(iy, 0, img.height - 1), yb = std::clamp(iy + 1, 0, img.height - 1);
  return {{img.px(xa, ya), img.px(xb, ya), img.px(xa, yb), img.px(xb, yb)},
          x - x0,
          y - y0,
          x >= 0.0f && y >= 0.0f && x <= static_cast<float>(img.width - 1) && y <= static_cast<float>(img.height - 1)};
}

// The interpolated RGBA value (all four channels, the CoC included, as a filtered texture gives it).
inline void bilinear_rgba(const BilinearTaps& t, float out[4]) {
  const float gx = 1.0f - t.fx, gy = 1.0f - t.fy;
  for (int ch = 0; ch < 4; ++ch) {
    const float top = t.texel[0][ch] * gx + t.texel[1][ch] * t.fx;
    const float bottom = t.texel[2][ch] * gx + t.texel[3][ch] * t.fx;
    out[ch] = top * gy + bottom * t.fy;
  }
}

// The four texels' bilinear weights, in texel order.
inline void bilinear_weights(const BilinearTaps& t, float w[4]) {
  const float gx = 1.0f - t.fx, gy = 1.0f - t.fy;
  w[0] = gx * gy, w[1] = t.fx * gy, w[2] = gx * t.fy, w[3] = t.fx * t.fy;
}

}  // namespace bokeh
