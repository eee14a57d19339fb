#pragma once
// What the engine-style gathers (spiral, hexagon) read: the colour with the CoC radius in alpha, signed
// as Godot's bokeh passes store it (in front of the focus plane negative, behind it positive), and
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

// A sample offset of the gathers, split into whole pixels and a fraction. The gathers sample every
// pixel at the same offsets, so the bilinear weights depend on the offset alone: computed once (on the
// CPU for the spiral's table, identically on both sides for the hexagon's), and neighbouring pixels
// share their texels (the GPU passes compute several adjacent pixels per invocation).
struct SubpixelOffset {
  int x_px, y_px;  // floor of the offset
  float fx, fy;    // offset - floor, in [0, 1)
};

inline SubpixelOffset split_offset(float dx_px, float dy_px) {
  const float x0 = std::floor(dx_px), y0 = std::floor(dy_px);
  return {static_cast<int>(x0), static_cast<int>(y0), dx_px - x0, dy_px - y0};
}

// Whether pixel (x, y) + o lies within the outermost pixel centres (every texel of non-zero weight in
// the image). The gathers skip other samples: light from beyond the image is absent, as in the exact
// reference (a texture sampler's clamp-to-edge would repeat the border pixels and smear them inwards).
inline bool sample_inside(const Image& img, int x, int y, const SubpixelOffset& o) {
  const int sx = x + o.x_px, sy = y + o.y_px;
  return sx >= 0 && sy >= 0 && (sx < img.width - 1 || (sx == img.width - 1 && o.fx == 0.0f)) &&
         (sy < img.height - 1 || (sy == img.height - 1 && o.fy == 0.0f));
}

// The four texels of pixel (x, y) + o, clamped to the image (only reached with weight 0 when the
// sample is inside): (sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1).
inline void bilinear_texels(const Image& img, int x, int y, const SubpixelOffset& o, const float* texel[4]) {
  const int sx = x + o.x_px, sy = y + o.y_px;
  const int xa = std::clamp(sx, 0, img.width - 1), xb = std::clamp(sx + 1, 0, img.width - 1);
  const int ya = std::clamp(sy, 0, img.height - 1), yb = std::clamp(sy + 1, 0, img.height - 1);
  texel[0] = img.px(xa, ya), texel[1] = img.px(xb, ya), texel[2] = img.px(xa, yb), texel[3] = img.px(xb, yb);
}

// The interpolated RGBA value (all four channels, the CoC included, as a filtered texture gives it).
// Mirrors bilinear_mix() in shaders/common/bilinear.glsl.
inline void bilinear_rgba(const float* const texel[4], const SubpixelOffset& o, float out[4]) {
  const float gx = 1.0f - o.fx, gy = 1.0f - o.fy;
  for (int ch = 0; ch < 4; ++ch) {
    const float top = texel[0][ch] * gx + texel[1][ch] * o.fx;
    const float bottom = texel[2][ch] * gx + texel[3][ch] * o.fx;
    out[ch] = top * gy + bottom * o.fy;
  }
}

// The four texels' bilinear weights, in texel order. Mirrors bilinear_weights().
inline void bilinear_weights(const SubpixelOffset& o, float w[4]) {
  const float gx = 1.0f - o.fx, gy = 1.0f - o.fy;
  w[0] = gx * gy, w[1] = o.fx * gy, w[2] = gx * o.fy, w[3] = o.fx * o.fy;
}

}  // namespace bokeh
