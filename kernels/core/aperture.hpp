#pragma once
// The lens's aperture: the shape each pixel's circle of confusion takes (issue 23). A disc, a regular
// polygon of n straight blades (5..9, rotated), or curved blades: a blend towards the disc.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bokeh {

// Image coordinates: x to the right, y down (rows), offsets in pixels from the source pixel's centre.
// A polygon of circumradius R has its vertex k at angle a_k = rotation + 2 pi k / n, measured clockwise
// from straight up: (R sin a_k, -R cos a_k); rotation 0 puts a vertex at the top.
// Curved blades (0 < curvature < 1): the disc of radius R intersected with the polygon enlarged by
// s = 1 + curvature (1 / cos(pi / n) - 1), i.e. whose inradius moves from R cos(pi / n) (straight
// blades) to R (curvature 1: the polygon holds the disc, so the shape is the disc). Convex throughout.
struct Aperture {
  int blades = 0;             // 0: a disc; 5..9: that many blades
  double rotation_deg = 0.0;  // clockwise on the image; 0: a vertex points up
  double curvature = 0.0;     // in [0, 1]: 0 straight blades, 1 the disc

  bool is_disc() const { return blades == 0; }
  // The radius at which offset (x, y) enters the shape: (x, y) lies in the shape of radius R exactly
  // when gauge(x, y) <= R (a norm: |p| for the disc, the polygon's scaled support for blades).
  double gauge(double x, double y) const;
  // Unchanged by the mirror y -> -y (FLAG's layer z then serves rows y + z and y - z): true for the disc,
  // and for n blades when n / 2 - n rotation / 180 is a whole number (a hexagon at 0, a pentagon at 90).
  bool vertically_symmetric() const;
  // Closed form of the shape's area at circumradius R: pi R^2, or n R^2 sin(2 pi / n) / 2 for straight
  // blades. Curved blades have no closed form here: NaN (the tests integrate them).
  double area(double radius_px) const;
  // The polygon's vertices at circumradius R (empty for the disc); curved blades: the enlarged polygon's.
  std::vector<std::pair<double, double>> polygon(double radius_px) const;
  // "disc", "blades6", "blades5-rot90", "blades6-curv0.3": what --aperture takes and point ids carry.
  std::string name() const;
  bool operator==(const Aperture&) const = default;
};

// Throws std::invalid_argument naming the field unless blades is 0 or 5..9, rotation finite within
// [-360, 360] and curvature within [0, 1] (and both 0 for the disc).
void validate(const Aperture& aperture);
// Parses Aperture::name()'s form ("disc", "blades<N>[-rot<deg>][-curv<c>]"); throws
// std::invalid_argument naming the text and the accepted form.
Aperture parse_aperture(const std::string& text);
// {"shape": "disc"} or {"shape": "polygon", "blades": n, "rotation_deg": a, "curvature": c, "name": ...}.
nlohmann::json aperture_json(const Aperture& aperture);
// A lens file's "aperture": the name as a string, or {"blades", "rotation_deg"?, "curvature"?}. Throws
// std::runtime_error naming `where` and the field.
Aperture aperture_from_json(const nlohmann::json& j, const std::string& where);

}  // namespace bokeh
