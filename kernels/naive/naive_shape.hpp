#pragma once
// The naive gather for any aperture (issue 23): a sample at offset (i k, j k) adds to a pixel when the
// source's shape reaches it, i.e. when the aperture's gauge of the offset is <= the source's radius, and
// it adds colour / (how many pattern offsets its shape covers). The disc keeps naive_gather.hpp's path.
#include <vector>

#include "aperture.hpp"
#include "coc_tiles.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// The pattern's offsets seen through an aperture. CPU and GPU compare the same floats (the table is
// uploaded as it is), so they agree on every shape test bit for bit.
// Every shape lies inside the disc of its circumradius (gauge >= |offset|), and each float gauge g is
// raised, by an ulp or two where rounding put it under, until in_disc(g * g, offset) holds: a radius r
// that covers an offset (g <= r) then has its disc cover it too. So disc bounds (the tile map of
// adaptive = on, a sprite's quad of side 2 floor(r) + 1) hold for every shape exactly, not only in
// exact arithmetic.
struct ShapeLattice {
  ShapeLattice(const Aperture& aperture, const GatherPattern& pattern);
  int side = 1;               // 2 n + 1
  std::vector<float> gauge;   // per offset, row (j) by row, left to right: Aperture::gauge(i k, j k) in float
  std::vector<float> sorted;  // the same, ascending: the area at radius r is how many are <= r
  // The number of pattern offsets inside the shape of radius r (>= 1 for r >= 0: the centre's gauge is 0).
  int area(float radius_px) const;
};

// The straightforward gather, one pixel at a time, rows then columns of the pattern (the order of
// shaders/naive/gather_shape.comp). color: >= 3 channels; radius_px: 1 channel, clamped to the pattern.
// tiles (adaptive = on): the tile-max CoC map of the radii (coc_tiles.hpp); each pixel then visits only
// the samples inside the disc of its tile's reach index D. A sample that adds lies inside its source's
// disc (ShapeLattice's guarantee), whose index is at most D: the same sums in the same order, bit for bit.
Image naive_shape_gather(const Image& color, const Image& radius_px, const ShapeLattice& lattice,
                         const GatherPattern& pattern, int threads = default_cpu_threads(),
                         const CocTiles* tiles = nullptr);

}  // namespace bokeh
