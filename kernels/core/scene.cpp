#include "scene.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "coc.hpp"
#include "image_io.hpp"

namespace bokeh {

namespace {

constexpr float kSkyDepth_m = 60.0f;

// Small deterministic hash so scenes are identical on every machine.
float hash01(int x, int y, int salt) {
  unsigned h = static_cast<unsigned>(x) * 374761393u + static_cast<unsigned>(y) * 668265263u +
               static_cast<unsigned>(salt) * 2246822519u;
  h = (h ^ (h >> 13)) * 1274126177u;
  return static_cast<float>((h ^ (h >> 16)) & 0xffffff) / static_cast<float>(0x1000000);
}

void put(Scene& s, int x, int y, float depth, float r, float g, float b) {
  if (x < 0 || y < 0 || x >= s.color.width || y >= s.color.height) return;
  float* c = s.color.px(x, y);
  c[0] = r, c[1] = g, c[2] = b;
  *s.depth_m.px(x, y) = depth;
}

Scene blank(const std::string& name, int w, int h) {
  Scene s{name, Image(w, h, 3), Image(w, h, 1, kSkyDepth_m), Lens{}};
  // A dim gradient backdrop with a little texture, far behind the focal plane.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float t = static_cast<float>(y) / h;
      const float n = 0.05f * hash01(x / 4, y / 4, 7);
      put(s, x, y, kSkyDepth_m, 0.10f + 0.10f * t + n, 0.12f + 0.08f * t + n, 0.18f + n);
    }
  return s;
}

// Scatter small HDR highlights over pixels whose depth lies in [near, far): bokeh discs show up there.
void sprinkle_highlights(Scene& s, float near_m, float far_m, float density, float radiance, int salt) {
  for (int y = 0; y < s.color.height; ++y)
    for (int x = 0; x < s.color.width; ++x) {
      const float d = *s.depth_m.px(x, y);
      if (d < near_m || d >= far_m || hash01(x, y, salt) > density) continue;
      const float hue = hash01(x, y, salt + 1);
      put(s, x, y, d, radiance * (0.6f + 0.4f * hue), radiance * 0.8f, radiance * (1.0f - 0.4f * hue));
    }
}

Scene hoops(int w, int h) {
  Scene s = blank("hoops", w, h);
  // Rings at depths in front of, at and behind the 3 m focus; nearer rings drawn last (they occlude).
  struct Hoop { float cx, cy, radius, thickness, depth_m, r, g, b; };
  const Hoop hoops[] = {
      {0.78f, 0.30f, 0.16f, 0.030f, 14.0f, 0.9f, 0.6f, 0.2f}, {0.22f, 0.35f, 0.18f, 0.035f, 7.0f, 0.2f, 0.7f, 0.9f},
      {0.55f, 0.60f, 0.20f, 0.040f, 3.0f, 0.9f, 0.9f, 0.9f},  {0.30f, 0.75f, 0.14f, 0.045f, 1.6f, 0.9f, 0.2f, 0.3f},
      {0.85f, 0.80f, 0.12f, 0.050f, 1.0f, 0.3f, 0.9f, 0.3f}};
  const float scale = static_cast<float>(std::min(w, h));
  for (const Hoop& hp : hoops)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float dx = (x - hp.cx * w) / scale, dy = (y - hp.cy * h) / scale;
        const float dist = std::sqrt(dx * dx + dy * dy);
        if (std::abs(dist - hp.radius) > hp.thickness) continue;
        const float shade = 0.6f + 0.4f * std::cos(12.0f * std::atan2(dy, dx));
        put(s, x, y, hp.depth_m, hp.r * shade, hp.g * shade, hp.b * shade);
      }
  sprinkle_highlights(s, 20.0f, 100.0f, 0.0005f, 40.0f, 11);  // sparse distant lights: discs read one by one
  sprinkle_highlights(s, 0.5f, 20.0f, 0.01f, 12.0f, 23);     // glints on the hoops
  return s;
}

Scene pillars(int w, int h) {
  Scene s = blank("pillars", w, h);
  // A receding row of pillars, far to near, with a ground plane whose depth grows towards the horizon.
  const int horizon = h / 2;
  for (int y = horizon; y < h; ++y) {
    const float t = static_cast<float>(y - horizon + 1) / (h - horizon);
    const float depth = std::clamp(1.2f / t, 1.2f, kSkyDepth_m);
    for (int x = 0; x < w; ++x) {
      const float checker = ((static_cast<int>(x / (8.0f / t + 1)) + static_cast<int>(depth * 2)) & 1) ? 0.35f : 0.2f;
      put(s, x, y, depth, checker, checker * 0.9f, checker * 0.7f);
    }
  }
  constexpr int kPillars = 7;
  for (int p = kPillars - 1; p >= 0; --p) {
    const float depth = 1.0f + 2.2f * static_cast<float>(p);  // 1 m .. 14.2 m
    const float cx = (0.12f + 0.76f * p / (kPillars - 1)) * w;
    const float half_width = std::max(2.0f, 0.05f * w * 2.0f / depth);
    for (int y = 0; y < h; ++y)
      for (int x = static_cast<int>(cx - half_width); x <= static_cast<int>(cx + half_width); ++x) {
        const float u = (x - cx) / half_width;
        const float light = 0.25f + 0.75f * std::max(0.0f, 1.0f - u * u);
        const bool band = (y / std::max(2, h / 24)) % 2 == 0;
        put(s, x, y, depth, light * (band ? 0.8f : 0.6f), light * 0.55f, light * 0.35f);
      }
  }
  sprinkle_highlights(s, 0.5f, 100.0f, 0.0006f, 30.0f, 31);
  return s;
}

Scene points(int w, int h) {
  Scene s{"points", Image(w, h, 3), Image(w, h, 1, 3.0f), Lens{}};  // dark backdrop at the focal plane
  for (const PointLight& p : point_lights(w, h)) put(s, p.x_px, p.y_px, p.depth_m, p.radiance, p.radiance, p.radiance);
  return s;
}

// A textured surface at (about) the focal plane: fine detail a blur would wipe out, with small
// highlights, depth within 0.5% of the focus distance (radii under a pixel at any usual f-stop).
void in_focus_wall(Scene& s, int x0, int x1, int salt) {
  const float focus = static_cast<float>(s.lens.focus_distance_m);
  for (int y = 0; y < s.color.height; ++y)
    for (int x = x0; x < x1; ++x) {
      const bool cell = ((x / 6) + (y / 6)) % 2 == 0;
      const float n = 0.15f * hash01(x, y, salt);
      const float depth = focus * (1.0f + 0.005f * (2.0f * hash01(x / 32, y / 32, salt + 1) - 1.0f));
      put(s, x, y, depth, (cell ? 0.55f : 0.25f) + n, (cell ? 0.45f : 0.22f) + n, (cell ? 0.30f : 0.35f) + n);
      if (hash01(x, y, salt + 2) < 0.002f) put(s, x, y, depth, 8.0f, 7.0f, 5.0f);
    }
}

// Distant lights: a dark far field with bright highlights (bokeh discs when defocused).
void far_lights(Scene& s, int x0, int x1, int y0, int y1, float depth_m, float density, int salt) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const float t = static_cast<float>(y) / s.color.height;
      put(s, x, y, depth_m, 0.05f + 0.08f * t, 0.06f + 0.05f * t, 0.12f);
      if (hash01(x, y, salt) < density) {
        const float hue = hash01(x, y, salt + 1);
        put(s, x, y, depth_m, 30.0f * (0.6f + 0.4f * hue), 24.0f, 30.0f * (1.0f - 0.4f * hue));
      }
    }
}

// A near, defocused blob (a leaf or a railing in front of the lens) centred at (cx, cy), radius in px.
void near_blob(Scene& s, float cx, float cy, float radius_px, float depth_m, int salt) {
  for (int y = std::max(0, static_cast<int>(cy - radius_px)); y <= std::min(s.color.height - 1, static_cast<int>(cy + radius_px)); ++y)
    for (int x = std::max(0, static_cast<int>(cx - radius_px)); x <= std::min(s.color.width - 1, static_cast<int>(cx + radius_px)); ++x) {
      if (std::hypot(x - cx, y - cy) > radius_px) continue;
      const float n = 0.1f * hash01(x, y, salt);
      put(s, x, y, depth_m, 0.15f + n, 0.45f + n, 0.12f);
    }
}

// Most of the frame on the focal plane: a textured wall at 3 m covering all but a corner, where
// distant lights (30 m) show through, and one small near blob (1.2 m): about a tenth defocused.
Scene mostly_in_focus(int w, int h) {
  Scene s = blank("mostly_in_focus", w, h);
  in_focus_wall(s, 0, w, 41);
  far_lights(s, w - w / 4, w, 0, h / 3, 30.0f, 0.004f, 43);
  near_blob(s, 0.12f * w, 0.85f * h, 0.06f * std::min(w, h), 1.2f, 47);
  return s;
}

// The left half on the focal plane, the right half a field of distant lights (25 m) with a near
// blob (1.5 m) straddling the edge.
Scene half_defocused(int w, int h) {
  Scene s = blank("half_defocused", w, h);
  in_focus_wall(s, 0, w / 2, 51);
  far_lights(s, w / 2, w, 0, h, 25.0f, 0.004f, 53);
  near_blob(s, 0.5f * w, 0.3f * h, 0.08f * std::min(w, h), 1.5f, 57);
  return s;
}

// Nothing on the focal plane: distant lights (40 m) everywhere, near blobs (1 m, 1.4 m) in front.
Scene fully_defocused(int w, int h) {
  Scene s = blank("fully_defocused", w, h);
  far_lights(s, 0, w, 0, h, 40.0f, 0.004f, 61);
  near_blob(s, 0.25f * w, 0.7f * h, 0.12f * std::min(w, h), 1.0f, 67);
  near_blob(s, 0.7f * w, 0.35f * h, 0.08f * std::min(w, h), 1.4f, 71);
  return s;
}

}  // namespace

std::vector<PointLight> point_lights(int w, int h) {
  // A 4x3 grid of lights, depths from 1 m (in front) through 3 m (in focus) to 40 m (behind).
  const float depths[] = {1.0f, 1.5f, 2.0f, 3.0f, 4.0f, 6.0f, 9.0f, 14.0f, 20.0f, 28.0f, 35.0f, 40.0f};
  std::vector<PointLight> lights;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 4; ++i)
      lights.push_back({(2 * i + 1) * w / 8, (2 * j + 1) * h / 6, depths[j * 4 + i], 100.0f});
  return lights;
}

const std::vector<std::string>& procedural_scene_names() {
  static const std::vector<std::string> names = {"hoops", "pillars", "points", "mostly_in_focus", "half_defocused",
                                                  "fully_defocused"};
  return names;
}

Scene make_scene(const std::string& name, int w, int h) {
  if (w < 16 || h < 16 || w > 16384 || h > 16384)
    throw std::invalid_argument(fmt::format("scene size {}x{} is outside 16..16384 px per side", w, h));
  if (name == "hoops") return hoops(w, h);
  if (name == "pillars") return pillars(w, h);
  if (name == "points") return points(w, h);
  if (name == "mostly_in_focus") return mostly_in_focus(w, h);
  if (name == "half_defocused") return half_defocused(w, h);
  if (name == "fully_defocused") return fully_defocused(w, h);
  std::string known;
  for (const auto& n : procedural_scene_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument(fmt::format("unknown scene '{}' (expected one of {})", name, known));
}

Scene load_scene(const std::string& color_path, const std::string& depth_path) {
  Scene s;
  s.name = color_path;
  s.color = read_image(color_path, 3, "colour");
  s.depth_m = read_image(depth_path, 1, "depth", /*float_only=*/true);
  if (s.color.width != s.depth_m.width || s.color.height != s.depth_m.height)
    throw std::runtime_error(fmt::format("colour '{}' is {}x{} but depth '{}' is {}x{}", color_path, s.color.width,
                                         s.color.height, depth_path, s.depth_m.width, s.depth_m.height));
  // Before any work, with the file named: the pixel check itself names the pixel.
  try {
    check_color(s.color);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("colour file '{}': {}", color_path, e.what()));
  }
  try {
    check_depth(s.depth_m);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("depth file '{}': {}", depth_path, e.what()));
  }
  return s;
}

}  // namespace bokeh
