#include "aperture.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <regex>
#include <stdexcept>

#include <fmt/format.h>

namespace bokeh {

namespace {

constexpr double kPi = std::numbers::pi;

// The enlargement of the polygon for curved blades (aperture.hpp).
double blade_scale(const Aperture& a) {
  return 1.0 + a.curvature * (1.0 / std::cos(kPi / a.blades) - 1.0);
}

}  // namespace

double Aperture::gauge(double x, double y) const {
  const double length = std::hypot(x, y);
  if (is_disc()) return length;
  // Edge k's outward normal points at angle m_k = rotation + 2 pi (k + 1/2) / n (clockwise from up),
  // at distance R cos(pi / n) from the centre.
  double support = -1e300;
  for (int k = 0; k < blades; ++k) {
    const double m = rotation_deg * kPi / 180.0 + 2.0 * kPi * (k + 0.5) / blades;
    support = std::max(support, x * std::sin(m) - y * std::cos(m));
  }
  const double polygon = support / (std::cos(kPi / blades) * blade_scale(*this));
  return curvature > 0 ? std::max(length, polygon) : polygon;
}

bool Aperture::vertically_symmetric() const {
  if (is_disc() || curvature >= 1.0) return true;
  const double turns = blades / 2.0 - blades * rotation_deg / 180.0;
  return std::abs(turns - std::round(turns)) < 1e-9;
}

double Aperture::area(double radius_px) const {
  if (is_disc() || curvature >= 1.0) return kPi * radius_px * radius_px;
  if (curvature > 0) return std::nan("");
  return blades * radius_px * radius_px * std::sin(2.0 * kPi / blades) / 2.0;
}

std::vector<std::pair<double, double>> Aperture::polygon(double radius_px) const {
  std::vector<std::pair<double, double>> v;
  if (is_disc()) return v;
  const double r = radius_px * blade_scale(*this);
  for (int k = 0; k < blades; ++k) {
    const double a = rotation_deg * kPi / 180.0 + 2.0 * kPi * k / blades;
    v.emplace_back(r * std::sin(a), -r * std::cos(a));
  }
  return v;
}

std::string Aperture::name() const {
  if (is_disc()) return "disc";
  std::string text = fmt::format("blades{}", blades);
  if (rotation_deg != 0) text += fmt::format("-rot{:g}", rotation_deg);
  if (curvature != 0) text += fmt::format("-curv{:g}", curvature);
  return text;
}

void validate(const Aperture& a) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("invalid aperture: " + what);
  };
  require(a.blades == 0 || (a.blades >= 5 && a.blades <= 9),
          fmt::format("blades must be 0 (a disc) or 5..9, got {}", a.blades));
  require(std::isfinite(a.rotation_deg) && std::abs(a.rotation_deg) <= 360,
          fmt::format("rotation_deg must be a finite angle within [-360, 360], got {}", a.rotation_deg));
  require(a.curvature >= 0 && a.curvature <= 1, fmt::format("curvature must be within [0, 1], got {}", a.curvature));
  require(!a.is_disc() || (a.rotation_deg == 0 && a.curvature == 0),
          "a disc takes no rotation_deg or curvature (give blades)");
}

Aperture parse_aperture(const std::string& text) {
  static const std::regex form(R"(blades([0-9]+)(-rot(-?[0-9]+(\.[0-9]+)?))?(-curv([0-9]+(\.[0-9]+)?))?)");
  Aperture a;
  std::smatch m;
  if (text == "disc") return a;
  if (!std::regex_match(text, m, form))
    throw std::invalid_argument(fmt::format(
        "aperture '{}' is not 'disc' or 'blades<N>[-rot<degrees>][-curv<0..1>]' (e.g. blades6, blades5-rot90, "
        "blades7-curv0.5)",
        text));
  a.blades = std::stoi(m[1].str());
  if (m[3].matched) a.rotation_deg = std::stod(m[3].str());
  if (m[6].matched) a.curvature = std::stod(m[6].str());
  try {
    validate(a);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("aperture '{}': {}", text, e.what()));
  }
  return a;
}

nlohmann::json aperture_json(const Aperture& a) {
  if (a.is_disc()) return {{"shape", "disc"}, {"name", a.name()}, {"vertically_symmetric", true}};
  return {{"shape", "polygon"},          {"name", a.name()},           {"blades", a.blades},
          {"rotation_deg", a.rotation_deg}, {"curvature", a.curvature}, {"vertically_symmetric", a.vertically_symmetric()}};
}

Aperture aperture_from_json(const nlohmann::json& j, const std::string& where) {
  try {
    if (j.is_string()) return parse_aperture(j.get<std::string>());
    if (!j.is_object())
      throw std::invalid_argument(fmt::format("must be a name (\"disc\", \"blades6\") or an object with blades, "
                                              "rotation_deg, curvature; not {}",
                                              j.type_name()));
    Aperture a;
    for (const auto& [key, value] : j.items()) {
      if (key != "blades" && key != "rotation_deg" && key != "curvature")
        throw std::invalid_argument(
            fmt::format("unknown field '{}' (expected blades, rotation_deg, curvature)", key));
      if (!value.is_number())
        throw std::invalid_argument(fmt::format("'{}' must be a number, not {} ({})", key, value.type_name(), value.dump()));
    }
    if (!j.contains("blades")) throw std::invalid_argument("lacks 'blades' (0 for a disc, or 5..9)");
    if (!j["blades"].is_number_integer()) throw std::invalid_argument(fmt::format("'blades' must be a whole number, not {}", j["blades"].dump()));
    a.blades = j["blades"].get<int>();
    a.rotation_deg = j.value("rotation_deg", 0.0);
    a.curvature = j.value("curvature", 0.0);
    validate(a);
    return a;
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{}: 'aperture': {}", where, e.what()));
  }
}

}  // namespace bokeh
