#pragma once
// Scenes: linear RGB colour plus planar view-space depth in metres. Procedural scenes are generated
// at any resolution so tests can stay small and sweeps can go large without shipping assets.
#include <string>
#include <vector>

#include "image.hpp"
#include "lens.hpp"

namespace bokeh {

struct Scene {
  std::string name;
  Image color;    // 3 channels, linear RGB, HDR allowed
  Image depth_m;  // 1 channel, planar depth in metres
  Lens lens;      // the scene's suggested camera
};

// A point light of the `points` scene: one pixel of `radiance` at a known depth.
struct PointLight {
  int x_px, y_px;
  float depth_m;
  float radiance;
};

// hoops, pillars, points; and, for the adaptive gathers, scenes that span the share of the frame out
// of focus: mostly_in_focus (about a tenth defocused), half_defocused, fully_defocused.
const std::vector<std::string>& procedural_scene_names();
// Throws std::invalid_argument for unknown names or sizes under 16x16.
Scene make_scene(const std::string& name, int width_px, int height_px);
// The lights `points` places at this resolution (exposed so tests can check disc size and position).
std::vector<PointLight> point_lights(int width_px, int height_px);

// Loads colour (first three channels) and depth (first channel) through OpenImageIO. Throws, naming
// the file and pixel, when a colour is not finite, a depth is not finite and > 0, or the depth file
// stores integers rather than floats (check_color, check_depth, read_image).
Scene load_scene(const std::string& color_path, const std::string& depth_path);

}  // namespace bokeh
