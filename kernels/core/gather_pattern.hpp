#pragma once
// The paper's N x N gather pattern at sample spacing k, and the disc test every gather method shares.
#include <cmath>
#include <stdexcept>
#include <string>

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
// disc misses column dx. The sqrt guess is corrected so the result matches in_disc exactly.
inline int disc_reach_layer(float radius_sq, int dx_px, int spacing_px, int max_layer) {
  if (!in_disc(radius_sq, dx_px, 0)) return -1;
  int z = static_cast<int>(std::sqrt(std::max(radius_sq - static_cast<float>(dx_px * dx_px), 0.0f)) / spacing_px);
  z = std::min(z, max_layer);
  while (z < max_layer && in_disc(radius_sq, dx_px, (z + 1) * spacing_px)) ++z;
  while (z > 0 && !in_disc(radius_sq, dx_px, z * spacing_px)) --z;
  return z;
}

// The disc's area counted in gather samples: how many pattern offsets (i k, j k) it covers.
// Dividing colour by this (rather than pi r^2) makes every source's contributions sum to exactly its
// colour, so radius 0 is the identity and energy is conserved.
inline int discrete_disc_area(float radius_px, const GatherPattern& p) {
  const float r2 = radius_px * radius_px;
  int area = 0;
  for (int i = -p.half(); i <= p.half(); ++i) {
    const int z = disc_reach_layer(r2, i * p.spacing_px, p.spacing_px, p.half());
    if (z >= 0) area += 2 * z + 1;
  }
  return area;
}

}  // namespace bokeh
