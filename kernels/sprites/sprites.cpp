#include "sprites.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include "naive_gather.hpp"

namespace bokeh {

nlohmann::json to_json(const SpriteStats& s) {
  return {{"sprites_detected", s.detected},
          {"sprites_drawn", s.drawn},
          {"sprites_overflowed", s.overflowed},
          {"sprite_overflow", s.overflowed > 0},
          {"max_sprites", s.max_sprites},
          {"sprite_quad_pixels", s.quad_pixels}};
}

float sprite_luminance(const float* rgb) { return 0.299f * rgb[0] + 0.587f * rgb[1] + 0.114f * rgb[2]; }

ShapeLattice sprite_shape_lattice(const Aperture& aperture, const GatherPattern& pattern) {
  const int max_px = static_cast<int>(pattern.max_radius_px());
  return ShapeLattice(aperture, GatherPattern{2 * max_px + 1, 1});
}

int disc_pixel_count(float radius_px) {
  const float r2 = radius_px * radius_px;
  const int f = static_cast<int>(radius_px);
  int count = 0;
  for (int dx = -f; dx <= f; ++dx) {
    const int z = disc_reach_layer(r2, dx, 1, f);
    if (z >= 0) count += 2 * z + 1;
  }
  return count;
}

SpriteDetection detect_sprites(const Image& color, const Image& packed, const SpriteSettings& s,
                               const ShapeLattice* shape) {
  if (color.channels < 3 || packed.channels != 4 || color.width != packed.width || color.height != packed.height)
    throw std::invalid_argument("sprites: colour (3+ channels) and packed input (4 channels) must match in size");
  SpriteDetection out;
  out.rest = packed;
  out.stats.max_sprites = s.max_sprites;
  const int w = color.width, h = color.height;
  // The same float operations in the same order as shaders/sprites/detect.comp.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float r = packed.px(x, y)[3];
      if (!(r >= s.min_radius_px)) continue;
      float neighbours[3] = {0, 0, 0};
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const float* c = color.px(std::clamp(x + dx, 0, w - 1), std::clamp(y + dy, 0, h - 1));
          for (int ch = 0; ch < 3; ++ch) neighbours[ch] += c[ch];
        }
      for (float& n : neighbours) n *= 0.125f;
      const float* c = color.px(x, y);
      const float contrast = sprite_luminance(c) - sprite_luminance(neighbours);
      if (!(contrast > s.threshold)) continue;
      ++out.stats.detected;
      if (out.stats.drawn >= s.max_sprites) {
        ++out.stats.overflowed;
        continue;
      }
      ++out.stats.drawn;
      Sprite sprite;
      sprite.x_px = x, sprite.y_px = y, sprite.radius_px = r;
      // The shape's offsets all lie in the quad (ShapeLattice: inside the disc), so the quad draws them all.
      const int count = shape ? shape->area(r) : disc_pixel_count(r);
      sprite.pixel_count = static_cast<float>(count);
      const float inv = 1.0f / static_cast<float>(count);
      for (int ch = 0; ch < 3; ++ch) sprite.rgb_per_pixel[ch] = c[ch] * inv;
      const std::int64_t side = 2 * static_cast<std::int64_t>(r) + 1;
      out.stats.quad_pixels += side * side;
      out.sprites.push_back(sprite);
      float* rest = out.rest.px(x, y);
      rest[0] = rest[1] = rest[2] = 0.0f;
    }
  return out;
}

void splat_sprites(Image& image, const std::vector<Sprite>& sprites, int threads, const ShapeLattice* shape) {
  if (image.channels < 3) throw std::invalid_argument("sprites: the image needs 3+ channels");
  const int half = shape ? (shape->side - 1) / 2 : 0;
  // What shaders/sprites/quad.frag tests: the disc, or the shape's table at the offset.
  const auto inside = [&](const Sprite& s, int dx, int dy) {
    if (!shape) return in_disc(s.radius_px * s.radius_px, dx, dy);
    if (std::abs(dx) > half || std::abs(dy) > half) return false;
    return shape->gauge[static_cast<std::size_t>(dy + half) * shape->side + (dx + half)] <= s.radius_px;
  };
  parallel_rows(image.height, threads, [&](int y) {
    for (const Sprite& s : sprites) {
      const int f = static_cast<int>(s.radius_px), dy = y - s.y_px;
      if (dy < -f || dy > f) continue;
      for (int dx = -f; dx <= f; ++dx) {
        const int x = s.x_px + dx;
        if (x < 0 || x >= image.width || !inside(s, dx, dy)) continue;
        float* o = image.px(x, y);
        for (int ch = 0; ch < 3; ++ch) o[ch] += s.rgb_per_pixel[ch];
      }
    }
  });
}

Image sprite_bokeh(const Image& color, const Image& packed, const GatherPattern& pattern, const SpriteSettings& settings,
                   int threads, SpriteStats* stats, const Aperture& aperture) {
  if (aperture.is_disc()) {
    SpriteDetection detection = detect_sprites(color, packed, settings);
    Image out = naive_gather(detection.rest, pattern, threads);
    splat_sprites(out, detection.sprites, threads);
    if (stats) *stats = detection.stats;
    return out;
  }
  const ShapeLattice shape = sprite_shape_lattice(aperture, pattern);
  SpriteDetection detection = detect_sprites(color, packed, settings, &shape);
  // naive's shape gather of the rest: the colour with the sprites' taken out (the GPU zeroes them in
  // the gather's weighted input, which gives the same zeros), the radii of the packed input.
  Image rest(color.width, color.height, 3), radius(color.width, color.height, 1);
  for (int y = 0; y < color.height; ++y)
    for (int x = 0; x < color.width; ++x) {
      for (int c = 0; c < 3; ++c) rest.px(x, y)[c] = color.px(x, y)[c];
      *radius.px(x, y) = packed.px(x, y)[3];
    }
  for (const Sprite& s : detection.sprites)
    for (int c = 0; c < 3; ++c) rest.px(s.x_px, s.y_px)[c] = 0.0f;
  Image out = naive_shape_gather(rest, radius, ShapeLattice(aperture, pattern), pattern, threads);
  splat_sprites(out, detection.sprites, threads, &shape);
  if (stats) *stats = detection.stats;
  return out;
}

}  // namespace bokeh
