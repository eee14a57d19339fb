#pragma once
// Thin-lens camera and the circle of confusion, FLAG paper equation (1).
#include <string>

#include "aperture.hpp"

namespace bokeh {

// Which image-plane distance the CoC uses. thin_lens: the true thin-lens image distance, giving
// equation (1) as printed, A f |D - P| / (D (P - f)). focal_plane_at_f: renderers such as Blender
// Cycles keep the image plane at the focal length, i.e. P in place of (P - f) (3-4% smaller radii).
enum class CocModel { thin_lens, focal_plane_at_f };

struct Lens {
  // Defaults: a portrait lens on a full-frame sensor; the procedural scenes sit around 3 m.
  double focal_length_mm = 85.0;
  double f_stop = 1.4;  // aperture diameter A = focal_length / f_stop
  double sensor_width_mm = 36.0;
  double focus_distance_m = 3.0;
  CocModel model = CocModel::thin_lens;
  Aperture aperture;  // the shape of every circle of confusion (a disc unless set)

  double aperture_diameter_mm() const { return focal_length_mm / f_stop; }
};

// Throws std::invalid_argument naming the offending field.
void validate(const Lens& lens);

// Reads {focal_length_mm, f_stop, sensor_width_mm, focus_distance_m[, coc_model][, aperture]}; throws with the
// file and field named on any problem.
Lens load_lens_json(const std::string& path);
std::string to_string(CocModel model);

// Equation (1) gives the CoC *diameter* on the sensor. Everything here uses the *radius* in pixels:
// r_px = coc_scale_px(lens, w) * |D - P| / D, with coc_scale_px = A f / (P - f) / 2 * (w / sensor_width).
double coc_scale_px(const Lens& lens, int image_width_px);
double coc_radius_px(const Lens& lens, double depth_m, int image_width_px);

}  // namespace bokeh
