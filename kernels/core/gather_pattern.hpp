#pragma once
// The paper's N x N gather pattern at sample spacing k, and the disc test every gather method shares.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace bokeh {

struct GatherPattern {
  int size_n = 41;      // samples per axis, odd
  int spacing_px = 2;   // k: distance between samples

  int half() const { return (size_n - 1) / 2; }
  // A 41x41 pattern at k=2 spans 81x81 pixels: the largest circle it holds has radius 40 px.
  float max_radius_px() const { return static_cast<float>(spacing_px * half()); }
  // FLAG's 3D buffer depth, ceil(N/2): layer z serves vertical offsets +-z*k.
  int layers() const { return half() + 1; }
  long samples_per_pixel() const { return static_cast<long>(size_n) * size_n; }
};

inline void validate(const GatherPattern& p) {
  if (p.size_n < 1 || p.size_n % 2 == 0)
    throw std::invalid_argument("gather size N must be odd and >= 1, got " + std::to_string(p.size_n));
  if (p.size_n > 201)
    throw std::invalid_argument("gather size N must be <= 201, got " + std::to_string(p.size_n));
  if (p.spacing_px < 1 || p.spacing_px > 64)
    throw std::invalid_argument("sample spacing k must be in [1, 64], got " + std::to_string(p.spacing_px));
}

// Disc membership is `float(dx^2 + dy^2) <= r^2` with integer offsets in pixels: exact integers in
// float, one rounding in r*r, so CPU and GPU (shaders/common/disc.glsl mirrors this) agree bit for bit.
inline bool in_disc(float radius_sq, int dx_px, int dy_px) {
  return static_cast<float>(dx_px * dx_px + dy_px * dy_px) <= radius_sq;
}

// Largest layer z (vertical offset z*k) that a disc reaches from horizontal offset dx, or -1 if the
// disc misses column dx. The sqrt guess is corrected so the result matches in_disc exactly. This and
// discrete_disc_area below are the definitions, straight from in_disc; the filters use the integer
// disc index further down, which the tests check against them.
inline int disc_reach_layer(float radius_sq, int dx_px, int spacing_px, int max_layer) {
  if (!in_disc(radius_sq, dx_px, 0)) return -1;
  // The guess is capped before the conversion: an infinite radius would make it undefined.
  const float guess = std::sqrt(std::max(radius_sq - static_cast<float>(dx_px * dx_px), 0.0f)) / spacing_px;
  int z = static_cast<int>(std::min(guess, static_cast<float>(max_layer)));
  while (z < max_layer && in_disc(radius_sq, dx_px, (z + 1) * spacing_px)) ++z;
  while (z > 0 && !in_disc(radius_sq, dx_px, z * spacing_px)) --z;
  return z;
}

// The disc's area counted in gather samples: how many pattern offsets (i k, j k) it covers.
// Dividing colour by this (rather than pi r^2) makes every source's contributions sum to exactly its
// colour, so radius 0 is the identity and energy is conserved. O(N); DiscAreaTable is O(1).
inline int discrete_disc_area(float radius_px, const GatherPattern& p) {
  const float r2 = radius_px * radius_px;
  int area = 0;
  for (int i = -p.half(); i <= p.half(); ++i) {
    const int z = disc_reach_layer(r2, i * p.spacing_px, p.spacing_px, p.half());
    if (z >= 0) area += 2 * z + 1;
  }
  return area;
}

// The share of the pattern's largest disc that lands inside a width x height frame, over all its
// pixels: every gather here skips samples outside the frame, so a method whose cost is its taps does
// this share of them. It falls as the pattern grows against the frame (800x600, k = 2: 0.90 at N = 81,
// 0.82 at N = 153), which holds a tap-bound method's growth in N below N^2 (figure9 reports both).
inline double disc_share_in_frame(const GatherPattern& p, int width_px, int height_px) {
  const float max_r2 = p.max_radius_px() * p.max_radius_px();
  double inside = 0, all = 0;  // pixel-sample pairs: (w - |dx|)+ pixels of a row see offset dx inside
  for (int i = -p.half(); i <= p.half(); ++i) {
    const int reach = disc_reach_layer(max_r2, i * p.spacing_px, p.spacing_px, p.half());
    if (reach < 0) continue;
    double column = 0;
    for (int j = -reach; j <= reach; ++j) column += std::max(height_px - std::abs(j) * p.spacing_px, 0);
    inside += std::max(width_px - std::abs(i) * p.spacing_px, 0) * column;
    all += 2.0 * reach + 1;
  }
  return inside / (all * width_px * height_px);
}

// The disc as an integer. Squared offsets on the pattern are integers, and float(int) rounds to
// nearest (ties to even) monotonically, so in_disc(radius_sq, dx, dy) holds exactly when
// dx^2 + dy^2 <= disc_threshold(radius_sq): the largest integer whose float is <= radius_sq. That is
// floor(radius_sq) below 2^24 (every integer a float); above, the integers up to half an ulp over
// radius_sq round down to it (the tie to the even one). -1 for NaN or negative.
inline std::int64_t disc_threshold(float radius_sq) {
  if (!(radius_sq >= 0.0f)) return -1;
  if (radius_sq < 16777216.0f) return static_cast<std::int64_t>(radius_sq);
  if (radius_sq >= 0x1p62f) return std::int64_t{1} << 62;  // beyond every pattern offset (and inf)
  const auto bits = std::bit_cast<std::uint32_t>(radius_sq);
  const int exponent = static_cast<int>((bits >> 23) & 0xffu) - 127;  // radius_sq in [2^e, 2^(e+1)): ulp 2^(e-23)
  return static_cast<std::int64_t>(radius_sq) + (std::int64_t{1} << (exponent - 24)) - (bits & 1u);
}

// floor(sqrt(d)) for d >= 0, exactly.
inline std::int64_t isqrt(std::int64_t d) {
  auto z = static_cast<std::int64_t>(std::sqrt(static_cast<double>(d)));
  while (z * z > d) --z;
  while ((z + 1) * (z + 1) <= d) ++z;
  return z;
}

// On a pattern of spacing k: in_disc(radius_sq, i k, j k) <=> i^2 + j^2 <= disc_index, which is
// floor(disc_threshold / k^2) (= floor(r^2 / k^2) below 2^24), capped at `cap` (pass 2 n^2, the
// largest i^2 + j^2 of the pattern: beyond it every sample is inside). -1: no sample (NaN radius).
inline int disc_index(float radius_sq, int spacing_px, int cap) {
  const std::int64_t t = disc_threshold(radius_sq);
  if (t < 0) return -1;
  return static_cast<int>(std::min<std::int64_t>(t / (static_cast<std::int64_t>(spacing_px) * spacing_px), cap));
}

// disc_reach_layer from the disc index: the largest z <= max_layer with i^2 + z^2 <= index, or -1
// if column i is outside the disc (i^2 > index).
inline int reach_layer(int index, int i, int max_layer) {
  const int d = index - i * i;
  if (d < 0) return -1;
  return static_cast<int>(std::min<std::int64_t>(isqrt(d), max_layer));
}

// discrete_disc_area for every radius at once: the area depends on the radius only through the disc
// index m, so area_by_index[m] = #{(i, j) in [-n, n]^2 : i^2 + j^2 <= m}, m = 0 .. 2 n^2. The CoC
// passes (CPU and shaders/common/coc.comp, which reads this table from a buffer) look it up in O(1).
class DiscAreaTable {
 public:
  explicit DiscAreaTable(const GatherPattern& p) : spacing_px_(p.spacing_px), max_index_(2 * p.half() * p.half()) {
    std::vector<std::int32_t> count(static_cast<std::size_t>(max_index_) + 1, 0);
    for (int j = -p.half(); j <= p.half(); ++j)
      for (int i = -p.half(); i <= p.half(); ++i) ++count[static_cast<std::size_t>(i * i + j * j)];
    by_index_.resize(count.size());
    std::int32_t sum = 0;
    for (std::size_t m = 0; m < count.size(); ++m) by_index_[m] = sum += count[m];
  }
  // discrete_disc_area(radius_px, pattern), in O(1).
  int area(float radius_px) const {
    const int m = disc_index(radius_px * radius_px, spacing_px_, max_index_);
    return m < 0 ? 0 : by_index_[static_cast<std::size_t>(m)];
  }
  int max_index() const { return max_index_; }
  const std::vector<std::int32_t>& by_index() const { return by_index_; }

 private:
  int spacing_px_, max_index_;
  std::vector<std::int32_t> by_index_;
};

}  // namespace bokeh
