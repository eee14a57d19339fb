#include "exact_scatter.hpp"
#include "fnv1a.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <type_traits>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>

#include "image_io.hpp"

namespace bokeh {

namespace {

// Bump when the reference changes, so stale cache files are never read back.
constexpr std::string_view kAlgorithmVersion =
    "exact_scatter v1: analytic coverage; additive-saturating layers; own surface continued behind nearer pixels";
// Bump when what a cache entry stores changes (2: the key and a pixel hash in the EXR header, checked on read).
constexpr std::string_view kCacheFormat = "reference cache format 2";
// The EXR header attributes of a cache entry: the key it was computed for, and a hash of its pixels.
constexpr const char* kKeyAttribute = "bokehReferenceKey";
constexpr const char* kPixelsAttribute = "bokehReferencePixels";

// ---- Disc / unit-square intersection, exact in closed form -------------------------------------------
// Disc of radius r centred at the origin. All offsets are from the source pixel's centre, so target
// pixel (dx, dy) is the square [dx-0.5, dx+0.5] x [dy-0.5, dy+0.5].

// Integral of sqrt(r^2 - s^2) for s in [0, x], x in [0, r].
double half_chord_integral(double r, double x) {
  return 0.5 * (x * std::sqrt(std::max(r * r - x * x, 0.0)) + r * r * std::asin(std::min(x / r, 1.0)));
}

// A horizontal line y = const (0 <= y) and where it leaves the disc: what every area on that line needs.
struct HorizontalEdge {
  double y;        // clamped to r
  double x_cross;  // sqrt(r^2 - y^2): the disc's half width at y
  double integral_at_cross;
  HorizontalEdge(double r, double y_abs) : y(std::min(y_abs, r)) {
    x_cross = std::sqrt(std::max(r * r - y * y, 0.0));
    integral_at_cross = half_chord_integral(r, x_cross);
  }
};

// Area of the disc inside [0, x] x [0, edge.y] for x >= 0; integral_at_x = half_chord_integral(r, min(x, r)).
double quadrant_area(double x, const HorizontalEdge& edge, double integral_at_x) {
  if (x <= edge.x_cross) return x * edge.y;  // the rectangle's far corner lies inside the disc
  return edge.y * edge.x_cross + integral_at_x - edge.integral_at_cross;
}

// Everything the scatter needs about one radius, for the quadrant |dx|, |dy| >= 0 (the disc is symmetric).
struct DiscStencil {
  int reach = 0;                  // largest |dx| or |dy| whose square overlaps the disc
  std::vector<int> inner;         // per |dy|: largest |dx| whose square lies wholly inside (coverage 1), or -1
  std::vector<int> edge_begin;    // per |dy| (+1 sentinel): where that row's partial coverages start
  std::vector<double> edge_coverage;  // per |dy|: coverage of |dx| = inner+1, inner+2, ... (all overlapping)
  double area = 1.0;              // sum of coverage over all pixels of the plane, both signs of dx and dy
};

int reach_of(float radius_px) {
  // A square at offset d overlaps the disc iff d - 0.5 < r. r <= 0.5: the disc stays in its own pixel.
  return radius_px <= 0.5f ? 0 : static_cast<int>(std::ceil(static_cast<double>(radius_px) + 0.5)) - 1;
}

DiscStencil make_disc_stencil(float radius_px) {
  DiscStencil st;
  st.reach = reach_of(radius_px);
  st.edge_begin.push_back(0);
  if (radius_px <= 0.5f) {  // the identity, by definition rather than by a pi r^2 / pi r^2 rounding
    st.inner.push_back(0);
    st.edge_begin.push_back(0);
    return st;
  }
  const double r = radius_px, r2 = r * r;  // exact: r has a 24 bit mantissa
  double area = 0.0;
  for (int dy = 0; dy <= st.reach; ++dy) {
    // Interior: the far corner (|dx|+0.5, |dy|+0.5) inside, tested exactly (halves and small integers).
    const double y_far = dy + 0.5;
    int inner = -1;
    if (y_far * y_far + 0.25 <= r2) {
      inner = static_cast<int>(std::floor(std::sqrt(r2 - y_far * y_far) - 0.5));
      while (inner >= 0 && (inner + 0.5) * (inner + 0.5) + y_far * y_far > r2) --inner;
      while ((inner + 1.5) * (inner + 1.5) + y_far * y_far <= r2) ++inner;
    }
    const double y_near = std::max(dy - 0.5, 0.0);
    const int outer = std::max(inner, static_cast<int>(std::ceil(std::sqrt(r2 - y_near * y_near) + 0.5)) - 1);

    // Area of the disc in the strip [0, x] x [dy-0.5, dy+0.5]; for dy = 0 the strip straddles y = 0.
    const HorizontalEdge top(r, dy + 0.5), bottom(r, std::abs(dy - 0.5));
    const double bottom_sign = dy == 0 ? -1.0 : 1.0;
    auto strip_area = [&](double x) {
      const double integral = half_chord_integral(r, std::min(x, r));
      return quadrant_area(x, top, integral) - bottom_sign * quadrant_area(x, bottom, integral);
    };
    // Coverage of |dx| = strip_area(dx + 0.5) - strip_area(dx - 0.5); the strip is odd in x.
    double left = inner >= 0 ? strip_area(inner + 0.5) : -strip_area(0.5);
    double row_area = inner >= 0 ? 2.0 * inner + 1.0 : 0.0;  // 1 per interior square
    for (int dx = inner + 1; dx <= outer; ++dx) {
      const double right = strip_area(dx + 0.5);
      const double coverage = right - left;
      st.edge_coverage.push_back(coverage);
      row_area += dx == 0 ? coverage : 2.0 * coverage;
      left = right;
    }
    st.inner.push_back(inner);
    st.edge_begin.push_back(static_cast<int>(st.edge_coverage.size()));
    area += dy == 0 ? row_area : 2.0 * row_area;
  }
  st.area = area;
  return st;
}


// ---- Any aperture (aperture.hpp): exact coverage of a pixel square by a convex shape ------------------
// The square is clipped against each edge of the (possibly enlarged) polygon, Sutherland-Hodgman: the
// result is convex, its area the shoelace sum. Curved blades intersect that with the disc: the area of
// a convex polygon inside a disc centred on the origin is the sum over its edges of the signed area of
// the triangle (origin, edge) inside the disc, each a triangle or a circular sector piece by piece.
using Point = std::pair<double, double>;

double cross(const Point& a, const Point& b) { return a.first * b.second - a.second * b.first; }

// Keeps the part of `poly` with n.p <= d.
std::vector<Point> clip_half_plane(const std::vector<Point>& poly, double nx, double ny, double d) {
  std::vector<Point> out;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point& p = poly[i];
    const Point& q = poly[(i + 1) % poly.size()];
    const double fp = nx * p.first + ny * p.second - d, fq = nx * q.first + ny * q.second - d;
    if (fp <= 0) out.push_back(p);
    if ((fp < 0 && fq > 0) || (fp > 0 && fq < 0)) {
      const double t = fp / (fp - fq);
      out.emplace_back(p.first + t * (q.first - p.first), p.second + t * (q.second - p.second));
    }
  }
  return out;
}

// Signed area of (triangle origin, a, b) inside the disc of radius r centred on the origin.
double triangle_in_disc(const Point& a, const Point& b, double r) {
  const double dx = b.first - a.first, dy = b.second - a.second;
  const double qa = dx * dx + dy * dy, qb = 2 * (a.first * dx + a.second * dy),
               qc = a.first * a.first + a.second * a.second - r * r;
  std::vector<double> cuts = {0.0};
  const double disc = qb * qb - 4 * qa * qc;
  if (qa > 0 && disc > 0) {
    const double root = std::sqrt(disc);
    for (double t : {(-qb - root) / (2 * qa), (-qb + root) / (2 * qa)})
      if (t > 0 && t < 1) cuts.push_back(t);
  }
  cuts.push_back(1.0);
  double area = 0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const Point p{a.first + cuts[i] * dx, a.second + cuts[i] * dy}, q{a.first + cuts[i + 1] * dx, a.second + cuts[i + 1] * dy};
    // A piece lies wholly inside or outside. Its midpoint decides, except where the edge only touches
    // the circle (no crossing): the midpoint is then on it, and the piece outside unless its ends are in.
    const double tm = 0.5 * (cuts[i] + cuts[i + 1]);
    const double mx = a.first + tm * dx, my = a.second + tm * dy;
    const bool ends_inside = std::max(p.first * p.first + p.second * p.second, q.first * q.first + q.second * q.second) <=
                             r * r * (1 + 1e-12);
    if (cuts.size() == 2 ? ends_inside : mx * mx + my * my <= r * r)
      area += 0.5 * cross(p, q);  // the piece lies inside: a triangle
    else
      area += 0.5 * r * r * std::atan2(cross(p, q), p.first * q.first + p.second * q.second);  // a sector
  }
  return area;
}

// Area of the shape of radius r (centred on the origin) inside [x0, x0+1] x [y0, y0+1].
double shape_square_coverage(const Aperture& aperture, const std::vector<Point>& polygon, double r, double x0,
                             double y0) {
  std::vector<Point> poly = {{x0, y0}, {x0 + 1, y0}, {x0 + 1, y0 + 1}, {x0, y0 + 1}};
  for (std::size_t k = 0; k < polygon.size() && !poly.empty(); ++k) {
    const Point& p = polygon[k];
    const Point& q = polygon[(k + 1) % polygon.size()];
    double nx = -(q.second - p.second), ny = q.first - p.first, d = nx * p.first + ny * p.second;
    if (d < 0) nx = -nx, ny = -ny, d = -d;  // outward: the centre lies inside
    poly = clip_half_plane(poly, nx, ny, d);
  }
  if (poly.size() < 3) return 0.0;
  double area = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point& a = poly[i];
    const Point& b = poly[(i + 1) % poly.size()];
    area += aperture.curvature > 0 ? triangle_in_disc(a, b, r) : 0.5 * cross(a, b);
  }
  return std::abs(area);
}

// The coverages of one radius of a shape that need not be symmetric: per row dy in [-reach, reach] the
// overlapped run of columns [first_dx, first_dx + count) and their coverages.
struct ShapeStencil {
  int reach = 0;
  std::vector<int> first_dx, begin;  // per row (begin: + 1 sentinel) into coverage
  std::vector<double> coverage;
  double area = 1.0;
};

// The shape's horizontal extent on the line at height y: [first, second], empty when first > second.
std::pair<double, double> extent_at(const Aperture& aperture, const std::vector<Point>& polygon, double r, double y) {
  double left = 1e300, right = -1e300;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    const Point& p = polygon[k];
    const Point& q = polygon[(k + 1) % polygon.size()];
    if (y < std::min(p.second, q.second) || y > std::max(p.second, q.second)) continue;
    const double x = p.second == q.second ? p.first : p.first + (y - p.second) / (q.second - p.second) * (q.first - p.first);
    const double x_other = p.second == q.second ? q.first : x;
    left = std::min({left, x, x_other}), right = std::max({right, x, x_other});
  }
  if (aperture.curvature > 0) {
    if (std::abs(y) > r) return {1, -1};
    const double half = std::sqrt(r * r - y * y);
    left = std::max(left, -half), right = std::min(right, half);
  }
  return {left, right};
}

// A superset of the shape's horizontal extent within the strip y0 <= y <= y1: the polygon's vertices
// inside the strip and its crossings of the strip's edges (for curved blades, within the disc's).
std::pair<double, double> extent_over(const Aperture& aperture, const std::vector<Point>& polygon, double r,
                                      double y0, double y1) {
  double left = 1e300, right = -1e300;
  for (const double y : {y0, y1}) {
    const auto [l, rt] = extent_at(Aperture{aperture.blades, aperture.rotation_deg, 0.0}, polygon, r, y);
    if (l <= rt) left = std::min(left, l), right = std::max(right, rt);
  }
  for (const Point& v : polygon)
    if (v.second >= y0 && v.second <= y1) left = std::min(left, v.first), right = std::max(right, v.first);
  if (aperture.curvature > 0) {
    const double nearest = y0 <= 0 && y1 >= 0 ? 0.0 : std::min(std::abs(y0), std::abs(y1));
    if (nearest > r) return {1, -1};
    const double half = std::sqrt(r * r - nearest * nearest);
    left = std::max(left, -half), right = std::min(right, half);
  }
  return {left, right};
}

ShapeStencil make_shape_stencil(const Aperture& aperture, float radius_px) {
  ShapeStencil st;
  st.reach = reach_of(radius_px);  // the shape lies within its circumscribed disc
  st.begin.push_back(0);
  if (radius_px <= 0.5f) {  // inside its own pixel: the identity, as for the disc
    st.first_dx.push_back(0);
    st.coverage.push_back(1.0);
    st.begin.push_back(1);
    return st;
  }
  const double r = radius_px;
  const std::vector<Point> polygon = aperture.polygon(r);
  double area = 0;
  std::vector<double> row(2 * st.reach + 1);
  for (int dy = -st.reach; dy <= st.reach; ++dy) {
    // Per row only the squares the shape's edge crosses are clipped (O(r) a stencil, not O(r^2)): a
    // convex shape holds a square exactly when it holds the square's top and bottom edges, i.e. when
    // [dx - 0.5, dx + 0.5] lies within its extents on both lines; outside the strip's extent it holds none.
    const double y0 = dy - 0.5, y1 = dy + 0.5;
    const auto top = extent_at(aperture, polygon, r, y0), bottom = extent_at(aperture, polygon, r, y1);
    const double inner_left = std::max(top.first, bottom.first), inner_right = std::min(top.second, bottom.second);
    const auto outer = extent_over(aperture, polygon, r, y0, y1);
    int first = 0, last = -1;  // an empty run until something overlaps (dx itself may be negative)
    for (int dx = -st.reach; dx <= st.reach; ++dx) {
      const double x0 = dx - 0.5, x1 = dx + 0.5;
      double c = 0.0;
      if (x0 >= inner_left && x1 <= inner_right) c = 1.0;
      else if (x1 > outer.first && x0 < outer.second) c = shape_square_coverage(aperture, polygon, r, x0, y0);
      row[dx + st.reach] = c;
      if (c > 0) {
        if (last < first) first = dx;
        last = dx;
      }
    }
    st.first_dx.push_back(first);
    if (last >= first)
      for (int dx = first; dx <= last; ++dx) st.coverage.push_back(row[dx + st.reach]), area += row[dx + st.reach];
    st.begin.push_back(static_cast<int>(st.coverage.size()));
  }
  st.area = area;
  return st;
}

template <class Add>
void for_each_overlapped_pixel_in_row(const ShapeStencil& st, int dy, int cx, int width, Add&& add) {
  const int row = dy + st.reach, begin = st.begin[row], count = st.begin[row + 1] - begin;
  for (int i = 0; i < count; ++i) {
    const int x = cx + st.first_dx[row] + i;
    if (x >= 0 && x < width) add(x, st.coverage[begin + i]);
  }
}

// Stencils by radius for one band of work: scenes repeat radii (one per surface depth), so most
// lookups hit; the map is emptied when it grows, which bounds memory for smoothly varying depth.
template <class Stencil>
class StencilCache {
 public:
  explicit StencilCache(const Aperture& aperture) : aperture_(aperture) {}
  const Stencil& get(float radius_px) {
    const auto key = std::bit_cast<std::uint32_t>(radius_px);
    if (auto it = stencils_.find(key); it != stencils_.end()) return it->second;
    if (stencils_.size() >= kCapacity) stencils_.clear();
    return stencils_.emplace(key, make(radius_px)).first->second;
  }

 private:
  Stencil make(float radius_px) const {
    if constexpr (std::is_same_v<Stencil, DiscStencil>) return make_disc_stencil(radius_px);
    else return make_shape_stencil(aperture_, radius_px);
  }
  static constexpr std::size_t kCapacity = 256;
  Aperture aperture_;
  std::unordered_map<std::uint32_t, Stencil> stencils_;
};

// Calls add(x, coverage) for every in-image pixel of the row dy below the shape's centre pixel cx
// (above for dy < 0) that the shape overlaps: the targets a source at cx reaches on that row.
template <class Add>
void for_each_overlapped_pixel_in_row(const DiscStencil& st, int dy, int cx, int width, Add&& add) {
  const int dy_abs = std::abs(dy);  // the disc is symmetric
  const int inner = st.inner[dy_abs];
  for (int x = std::max(cx - inner, 0), end = std::min(cx + inner, width - 1); x <= end; ++x) add(x, 1.0);
  const int begin = st.edge_begin[dy_abs], count = st.edge_begin[dy_abs + 1] - begin;
  for (int i = 0; i < count; ++i) {
    const int dx = inner + 1 + i;
    const double coverage = st.edge_coverage[begin + i];
    if (cx + dx < width) add(cx + dx, coverage);
    if (dx != 0 && cx - dx >= 0) add(cx - dx, coverage);
  }
}

void validate_inputs(const Image& color, const Image& radius_px, const Image& depth_m, ScatterComposite mode) {
  if (color.channels < 3) throw std::invalid_argument("exact_scatter: colour needs at least three channels");
  if (radius_px.channels != 1 || radius_px.width != color.width || radius_px.height != color.height)
    throw std::invalid_argument(fmt::format("exact_scatter: radius must be 1 channel of {}x{}, got {} of {}x{}",
                                            color.width, color.height, radius_px.channels, radius_px.width,
                                            radius_px.height));
  for (std::size_t i = 0; i < radius_px.pixels.size(); ++i)
    if (!std::isfinite(radius_px.pixels[i]) || radius_px.pixels[i] < 0.0f)
      throw std::invalid_argument(fmt::format("exact_scatter: radius at pixel ({}, {}) is {}: must be finite, >= 0",
                                              i % color.width, i / color.width, radius_px.pixels[i]));
  if (mode != ScatterComposite::depth_ordered) return;
  if (depth_m.channels != 1 || depth_m.width != color.width || depth_m.height != color.height)
    throw std::invalid_argument(fmt::format("exact_scatter: depth must be 1 channel of {}x{}, got {} of {}x{}",
                                            color.width, color.height, depth_m.channels, depth_m.width,
                                            depth_m.height));
  for (std::size_t i = 0; i < depth_m.pixels.size(); ++i)
    if (!std::isfinite(depth_m.pixels[i]))
      throw std::invalid_argument(fmt::format("exact_scatter: depth at pixel ({}, {}) is {}: must be finite",
                                              i % color.width, i / color.width, depth_m.pixels[i]));
}

// Work is split into bands of target rows, each owned by one thread: a gather formulation of the
// scatter, so no two threads write the same pixel. Several bands per thread even out uneven cost.
struct Bands {
  int height_px, count;
  Bands(int image_height, int threads)
      : height_px(std::max(1, (image_height + 4 * threads - 1) / (4 * threads))),
        count((image_height + height_px - 1) / height_px) {}
};

// Both modes write out[(y * width + x) * 3 + k], which the caller sized; each band writes only its rows.
template <class Stencil>
void scatter_energy_sum(const Image& color, const Image& radius_px, const Aperture& aperture, int threads,
                        std::vector<double>& out) {
  const int w = color.width, h = color.height;
  const float max_radius = *std::max_element(radius_px.pixels.begin(), radius_px.pixels.end());
  const int max_reach = reach_of(max_radius);
  const Bands bands(h, threads);
  parallel_rows(bands.count, threads, [&](int band) {
    const int y0 = band * bands.height_px, y1 = std::min(h, y0 + bands.height_px);
    double* sum = out.data() + static_cast<std::size_t>(y0) * w * 3;
    StencilCache<Stencil> stencils(aperture);
    for (int sy = std::max(0, y0 - max_reach); sy < std::min(h, y1 + max_reach); ++sy)
      for (int sx = 0; sx < w; ++sx) {
        const float r = *radius_px.px(sx, sy);
        const int reach = reach_of(r);
        if (sy + reach < y0 || sy - reach >= y1) continue;
        const float* c = color.px(sx, sy);
        if (c[0] == 0.0f && c[1] == 0.0f && c[2] == 0.0f) continue;  // adds nothing
        const Stencil& st = stencils.get(r);
        const double scale[3] = {c[0] / st.area, c[1] / st.area, c[2] / st.area};
        for (int ty = std::max(y0, sy - reach); ty < std::min(y1, sy + reach + 1); ++ty) {
          double* row = sum + static_cast<std::size_t>(ty - y0) * w * 3;
          for_each_overlapped_pixel_in_row(st, ty - sy, sx, w, [&](int tx, double coverage) {
            double* t = row + 3 * tx;
            for (int k = 0; k < 3; ++k) t[k] += coverage * scale[k];
          });
        }
      }
  });
}

template <class Stencil>
void scatter_depth_ordered(const Image& color, const Image& radius_px, const Image& depth_m, const Aperture& aperture,
                           int threads, std::vector<double>& out) {
  // Views this close to full count as full: spares the hidden-surface pass the rounding residue of
  // interiors, whose shares sum to 1 only up to rounding.
  constexpr double kFullView = 1.0 - 1e-9;
  const int w = color.width, h = color.height;
  // Front to back; equal depths end up adjacent and form one layer.
  std::vector<std::uint32_t> order(color.pixel_count());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return depth_m.pixels[a] < depth_m.pixels[b]; });
  const Bands bands(h, threads);
  parallel_rows(bands.count, threads, [&](int band) {
    const int y0 = band * bands.height_px, y1 = std::min(h, y0 + bands.height_px);
    const std::size_t band_px = static_cast<std::size_t>(y1 - y0) * w;
    std::vector<double> rgb(band_px * 3, 0.0), alpha(band_px, 0.0);
    std::vector<double> layer_rgb(band_px * 3, 0.0), layer_weight(band_px, 0.0);
    std::vector<std::size_t> touched;  // band pixels the current layer reached
    StencilCache<Stencil> stencils(aperture);
    for (std::size_t first = 0; first < order.size();) {
      const float layer_depth = depth_m.pixels[order[first]];
      std::size_t end = first;
      for (; end < order.size() && depth_m.pixels[order[end]] == layer_depth; ++end) {
        const int sx = static_cast<int>(order[end] % w), sy = static_cast<int>(order[end] / w);
        const float r = *radius_px.px(sx, sy);
        const int reach = reach_of(r);
        if (sy + reach < y0 || sy - reach >= y1) continue;
        const Stencil& st = stencils.get(r);
        const float* c = color.px(sx, sy);
        for (int ty = std::max(y0, sy - reach); ty < std::min(y1, sy + reach + 1); ++ty) {
          const std::size_t row = static_cast<std::size_t>(ty - y0) * w;
          for_each_overlapped_pixel_in_row(st, ty - sy, sx, w, [&](int tx, double coverage) {
            const std::size_t t = row + tx;
            if (alpha[t] >= 1.0 || coverage <= 0.0) return;  // view already full, or a rounding-zero sliver
            if (layer_weight[t] == 0.0) touched.push_back(t);
            const double weight = coverage / st.area;
            layer_weight[t] += weight;
            for (int k = 0; k < 3; ++k) layer_rgb[3 * t + k] += weight * c[k];
          });
        }
      }
      for (std::size_t t : touched) {
        const double f = std::min(1.0, (1.0 - alpha[t]) / layer_weight[t]);
        for (int k = 0; k < 3; ++k) rgb[3 * t + k] += f * layer_rgb[3 * t + k], layer_rgb[3 * t + k] = 0.0;
        alpha[t] += f * layer_weight[t];
        layer_weight[t] = 0.0;
      }
      touched.clear();
      first = end;
    }
    // The surface seen at t continues behind nearer pixels and beyond the border: the share its disc
    // would have had there is filled, up to a full view, with the mean colour of what the view shows.
    for (std::size_t t = 0; t < band_px; ++t) {
      if (alpha[t] >= kFullView || alpha[t] <= 0.0) continue;
      const int tx = static_cast<int>(t % w), ty = y0 + static_cast<int>(t / w);
      const float own_depth = *depth_m.px(tx, ty);
      const Stencil& st = stencils.get(*radius_px.px(tx, ty));
      double in_image = 0.0, nearer = 0.0;
      for (int py = std::max(0, ty - st.reach); py <= std::min(h - 1, ty + st.reach); ++py)
        for_each_overlapped_pixel_in_row(st, py - ty, tx, w, [&](int px, double coverage) {
          in_image += coverage;
          if (*depth_m.px(px, py) < own_depth) nearer += coverage;
        });
      const double hidden = (nearer + st.area - in_image) / st.area;
      const double fill = std::clamp(hidden, 0.0, 1.0 - alpha[t]);
      for (int k = 0; k < 3; ++k) rgb[3 * t + k] *= (alpha[t] + fill) / alpha[t];
      alpha[t] += fill;
    }
    std::copy(rgb.begin(), rgb.end(), out.begin() + static_cast<std::ptrdiff_t>(y0) * w * 3);
  });
}

void fnv1a_image(std::uint64_t& hash, const Image& image) {
  const int shape[3] = {image.width, image.height, image.channels};
  fnv1a(hash, shape, sizeof shape);
  fnv1a(hash, image.pixels.data(), image.pixels.size() * sizeof(float));
}

}  // namespace

std::string to_string(ScatterComposite mode) {
  return mode == ScatterComposite::energy_sum ? "energy_sum" : "depth_ordered";
}

std::vector<double> exact_scatter_double(const Image& color, const Image& radius_px, const Image& depth_m,
                                         ScatterComposite mode, int threads, const Aperture& aperture) {
  validate_inputs(color, radius_px, depth_m, mode);
  validate(aperture);
  std::vector<double> out(color.pixel_count() * 3, 0.0);
  if (out.empty()) return out;
  // The disc keeps its own closed form (circular segments, symmetric stencils); other shapes clip.
  if (mode == ScatterComposite::energy_sum && aperture.is_disc())
    scatter_energy_sum<DiscStencil>(color, radius_px, aperture, threads, out);
  else if (mode == ScatterComposite::energy_sum)
    scatter_energy_sum<ShapeStencil>(color, radius_px, aperture, threads, out);
  else if (aperture.is_disc())
    scatter_depth_ordered<DiscStencil>(color, radius_px, depth_m, aperture, threads, out);
  else
    scatter_depth_ordered<ShapeStencil>(color, radius_px, depth_m, aperture, threads, out);
  return out;
}

Image exact_scatter(const Image& color, const Image& radius_px, const Image& depth_m, ScatterComposite mode,
                    int threads, const Aperture& aperture) {
  const std::vector<double> rgb = exact_scatter_double(color, radius_px, depth_m, mode, threads, aperture);
  Image out(color.width, color.height, 3);
  std::transform(rgb.begin(), rgb.end(), out.pixels.begin(), [](double v) { return static_cast<float>(v); });
  return out;
}

std::uint64_t exact_scatter_key(const Image& color, const Image& radius_px, const Image& depth_m,
                                ScatterComposite mode, const Aperture& aperture) {
  std::uint64_t hash = kFnv1aOffset;
  fnv1a(hash, kAlgorithmVersion.data(), kAlgorithmVersion.size());
  fnv1a(hash, kCacheFormat.data(), kCacheFormat.size());
  const int mode_id = static_cast<int>(mode);
  fnv1a(hash, &mode_id, sizeof mode_id);
  fnv1a_image(hash, color);
  fnv1a_image(hash, radius_px);
  if (mode == ScatterComposite::depth_ordered) fnv1a_image(hash, depth_m);
  if (!aperture.is_disc()) {  // the disc hashes as before, so existing cache entries stay valid
    const std::string shape = aperture.name();
    fnv1a(hash, shape.data(), shape.size());
  }
  return hash;
}

ExactReferenceCache::ExactReferenceCache(std::filesystem::path directory) : directory_(std::move(directory)) {}

std::filesystem::path ExactReferenceCache::path_for(const Image& color, const Image& radius_px, const Image& depth_m,
                                                    ScatterComposite mode, const Aperture& aperture) const {
  return directory_ / fmt::format("exact-{}-{}{}x{}-{:016x}.exr", to_string(mode),
                                  aperture.is_disc() ? "" : aperture.name() + "-", color.width, color.height,
                                  exact_scatter_key(color, radius_px, depth_m, mode, aperture));
}

namespace {

std::string pixels_hash(const Image& image) {
  std::uint64_t hash = kFnv1aOffset;
  fnv1a_image(hash, image);
  return fmt::format("{:016x}", hash);
}

// Why a stored entry cannot be used for `key`, or empty when it can (`cached` then holds it).
std::string check_entry(const std::filesystem::path& path, const std::string& key, const Image& color, Image& cached) {
  try {
    const std::string stored_key = read_image_attribute(path.string(), kKeyAttribute);
    if (stored_key.empty()) return "carries no key (written by an older bokehbench, or not by bokehbench)";
    if (stored_key != key) return fmt::format("was computed for other inputs (key {}, expected {})", stored_key, key);
    cached = read_image(path.string(), 3, "cached reference");
    if (cached.width != color.width || cached.height != color.height)
      return fmt::format("is {}x{}, expected {}x{}", cached.width, cached.height, color.width, color.height);
    if (pixels_hash(cached) != read_image_attribute(path.string(), kPixelsAttribute))
      return "has pixels that do not match the hash stored with them";
  } catch (const std::runtime_error& e) {
    return fmt::format("cannot be read ({})", e.what());  // e.g. truncated by a crash
  }
  return {};
}

}  // namespace

Image ExactReferenceCache::get(const Image& color, const Image& radius_px, const Image& depth_m,
                               ScatterComposite mode, int threads, const Aperture& aperture) {
  validate_inputs(color, radius_px, depth_m, mode);
  const std::filesystem::path path = path_for(color, radius_px, depth_m, mode, aperture);
  const std::string key = fmt::format("{:016x}", exact_scatter_key(color, radius_px, depth_m, mode, aperture));
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    Image cached;
    const std::string problem = check_entry(path, key, color, cached);
    if (problem.empty()) return cached;
    fmt::print(stderr, "note: reference cache entry '{}' {}: recomputing it\n", path.string(), problem);
  }
  Image reference = exact_scatter(color, radius_px, depth_m, mode, threads, aperture);
  std::filesystem::create_directories(directory_);
  // Atomic (write_file_atomically): concurrent processes never read half a file.
  write_image(reference, path.string(), {{kKeyAttribute, key}, {kPixelsAttribute, pixels_hash(reference)}});
  return reference;
}

}  // namespace bokeh
