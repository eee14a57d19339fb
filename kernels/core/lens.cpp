#include "lens.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "text_file.hpp"

namespace bokeh {

void validate(const Lens& lens) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(fmt::format("invalid lens: {}", what));
  };
  require(std::isfinite(lens.focal_length_mm) && lens.focal_length_mm > 0, "focal_length_mm must be > 0");
  require(lens.f_stop > 0 && !std::isnan(lens.f_stop), "f_stop must be > 0 (a huge f_stop is a pinhole)");
  require(std::isfinite(lens.sensor_width_mm) && lens.sensor_width_mm > 0, "sensor_width_mm must be > 0");
  require(std::isfinite(lens.focus_distance_m) && lens.focus_distance_m * 1000.0 > lens.focal_length_mm,
          "focus_distance_m must be finite and beyond the focal length (nothing nearer can be focused)");
  validate(lens.aperture);
}

std::string to_string(CocModel model) {
  return model == CocModel::thin_lens ? "thin_lens" : "focal_plane_at_f";
}

Lens load_lens_json(const std::string& path) {
  const std::string text = read_text_file(path, "lens file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(fmt::format("lens file '{}' is not valid JSON: {}", path, e.what()));
  }
  if (!j.is_object())
    throw std::runtime_error(fmt::format("lens file '{}' must hold a JSON object, not {}", path, j.type_name()));
  static const char* kFields[] = {"focal_length_mm", "f_stop", "sensor_width_mm", "focus_distance_m", "coc_model", "aperture"};
  for (const auto& [key, value] : j.items())
    if (std::find(std::begin(kFields), std::end(kFields), key) == std::end(kFields))
      throw std::runtime_error(fmt::format(
          "lens file '{}': unknown field '{}' (expected focal_length_mm, f_stop, sensor_width_mm, focus_distance_m, "
          "coc_model, aperture)",
          path, key));
  Lens lens;
  auto number = [&](const char* key) {
    if (!j.contains(key)) throw std::runtime_error(fmt::format("lens file '{}' lacks '{}'", path, key));
    if (!j[key].is_number())
      throw std::runtime_error(
          fmt::format("lens file '{}': '{}' must be a number, not {} ({})", path, key, j[key].type_name(), j[key].dump()));
    return j[key].get<double>();
  };
  lens.focal_length_mm = number("focal_length_mm");
  lens.f_stop = number("f_stop");
  lens.sensor_width_mm = number("sensor_width_mm");
  lens.focus_distance_m = number("focus_distance_m");
  if (j.contains("coc_model")) {
    if (!j["coc_model"].is_string())
      throw std::runtime_error(fmt::format("lens file '{}': 'coc_model' must be a string (thin_lens or "
                                           "focal_plane_at_f), not {} ({})",
                                           path, j["coc_model"].type_name(), j["coc_model"].dump()));
    const auto model = j["coc_model"].get<std::string>();
    if (model == "thin_lens") lens.model = CocModel::thin_lens;
    else if (model == "focal_plane_at_f") lens.model = CocModel::focal_plane_at_f;
    else throw std::runtime_error(fmt::format("lens file '{}': coc_model '{}' is not thin_lens or focal_plane_at_f", path, model));
  }
  if (j.contains("aperture")) lens.aperture = aperture_from_json(j["aperture"], fmt::format("lens file '{}'", path));
  try {
    validate(lens);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("lens file '{}': {}", path, e.what()));
  }
  return lens;
}

double coc_scale_px(const Lens& lens, int image_width_px) {
  const double focus_mm = lens.focus_distance_m * 1000.0;
  const double image_distance_term_mm =
      lens.model == CocModel::thin_lens ? focus_mm - lens.focal_length_mm : focus_mm;
  const double diameter_per_unit_mm = lens.aperture_diameter_mm() * lens.focal_length_mm / image_distance_term_mm;
  return 0.5 * diameter_per_unit_mm * image_width_px / lens.sensor_width_mm;
}

double coc_radius_px(const Lens& lens, double depth_m, int image_width_px) {
  return coc_scale_px(lens, image_width_px) * std::abs(depth_m - lens.focus_distance_m) / depth_m;
}

}  // namespace bokeh
