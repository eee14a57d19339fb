#pragma once
// FLAG for any convex aperture (issue 23): per-layer chord extents of the shape. A row sample at
// column offset i k with radius r covers the rows dz k of its shape's vertical chord at x = i k,
// dz in [lo, hi] (an interval: the shape is convex; it need not hold dz = 0, e.g. a pentagon pointing
// up). The horizontal pass bins it as a difference along the layers, +colour at the chord's far end
// hi and -colour just past its near end lo - 1, and accumulates from the outermost layer inwards as
// the disc's FLAG does, so layer dz holds exactly the samples whose chord covers dz: O(N) per pixel.
//
// Layers: a shape unchanged by the mirror y -> -y (Aperture::vertically_symmetric, and its float
// lattice mirror-exact) has chords [-h, h]: one half, (N + 1) / 2 layers z = |dz| as for the disc
// (paper 3.2.2: halved memory), binned at h alone. Any other shape keeps both halves, N layers
// z = dz + n, and the vertical pass reads layer n - j for row y + j k (the source j rows below the
// pixel covers it when its chord holds dz = -j).
//
// Which offsets are inside is naive's shape test (naive_shape.hpp): the chords come from the same
// float gauges (ShapeLattice), so FLAG and naive-shape draw the same offsets, and weights are colour /
// area with area = the pattern offsets inside the shape of that radius (ShapeLattice::area).
#include <cstdint>
#include <string>
#include <vector>

#include "aperture.hpp"
#include "flag.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "naive_shape.hpp"
#include "parallel.hpp"

namespace bokeh {

// The chord table. A source's shape is the first m offsets of the lattice in ascending gauge, where
// m = ShapeLattice::area(r): m is also its area. chords[column * (side^2 + 1) + m] is the chord of
// lattice column `column` (offset from source to pixel (column - n) k) for area m, packed as
// (hi + n + 1) << 16 | (lo + n), 0 when the column is outside the shape (lo = -n > hi = -n - 1).
// One load per sample and output column on the GPU: a search in per-column monotone tables would
// cost log2(N) loads instead, each of which lavapipe turns into 8 scalar loads in the horizontal
// pass's non-uniform control flow; the table is side x (side^2 + 1) ints (276 KiB at N = 41).
// After them, side ints: reach(column), the smallest area whose chord is not 0 in that column or any
// farther from the centre on its side (0 at the centre). A source whose area is below reach(column)
// has no chord in that column nor beyond it: the fused pass skips, without changing a bit, the samples
// that reach none of a subgroup's columns (one load for the nearest instead of a chord for each).
//
// The row sections, for the scan binning (horizontal_bins = scan, shaders/flag/horizontal_shape_scan.comp):
// the lattice columns c whose chord for area m covers layer z (halved: hi >= z; both halves: lo <= z - n
// <= hi), i.e. the shape's row dz = z (halved) or z - n. A convex shape's row is an interval [a, b]:
// the source at row offset j adds to the output columns j + a - n .. j + b - n of its phase, an
// interval sum. Packed as (b + 1) << 16 | a, 0 when the row is outside the shape. Laid out for the
// GPU's workgroups of 8 layers (one invocation a layer): per (area m, group g of layers 8 g .. 8 g + 7),
// kSectionInts ints (three ivec4): the 8 layers' sections (0 past the layer count), then their union
// [min a, max b] (0: none; the skip test of the whole group), then 3 ints of 0.
struct FlagShapeTable {
  FlagShapeTable(const Aperture& aperture, const GatherPattern& pattern);
  // From a lattice as given (the tests make shapes no Aperture draws); `aperture` names it and says
  // whether it is vertically symmetric. Throws std::logic_error where a column's chord or a layer's
  // row section is not an interval (a shape that is not convex there).
  FlagShapeTable(const Aperture& aperture, ShapeLattice lattice, const GatherPattern& pattern);
  static constexpr int kSectionInts = 12;
  ShapeLattice lattice;  // naive's gauges: area and shape test
  int half_n = 0, side = 1;
  bool halved = false;  // one half of the layers: the lattice is mirror-exact (see above)
  std::vector<std::int32_t> chords;
  std::vector<std::int32_t> sections;  // [(m * layer_groups() + g) * kSectionInts + i], see above
  int layers() const { return halved ? half_n + 1 : side; }
  int layer_groups() const { return (layers() + 7) / 8; }
  std::int32_t chord(int column, int area) const {
    return chords[static_cast<std::size_t>(column) * (static_cast<std::size_t>(side) * side + 1) + area];
  }
  std::int32_t reach(int column) const {
    return chords[static_cast<std::size_t>(side) * (static_cast<std::size_t>(side) * side + 1) + column];
  }
  // The row section of area m and layer z, and the union of group g's: packed as above.
  std::int32_t section(int area, int layer) const {
    return sections[(static_cast<std::size_t>(area) * layer_groups() + layer / 8) * kSectionInts + layer % 8];
  }
  std::int32_t section_union(int area, int group) const {
    return sections[(static_cast<std::size_t>(area) * layer_groups() + group) * kSectionInts + 8];
  }
  std::uint64_t chord_bytes() const { return chords.size() * sizeof(std::int32_t); }
  std::uint64_t section_bytes() const { return sections.size() * sizeof(std::int32_t); }
  // The table the GPU's horizontal pass reads: the row sections (scan) or the chords (indexed, masked).
  std::uint64_t bytes(bool scan) const { return scan ? section_bytes() : chord_bytes(); }
  // bytes(scan) of any aperture's table with `layers` layers on this pattern, without building it.
  static std::uint64_t bytes_for(const GatherPattern& pattern, int layers, bool scan);
};

// Whether FLAG keeps one half of the layers for this aperture: vertically symmetric and its float
// lattice mirror-exact (FlagShapeTable::halved).
bool flag_layers_halved(const Aperture& aperture, const ShapeLattice& lattice);
// Layers FLAG stores for this aperture: (N + 1) / 2 for the disc and mirror-symmetric shapes, N for
// the others (FlagShapeTable::layers()), from the lattice alone (no chord table).
int flag_aperture_layers(const Aperture& aperture, const GatherPattern& pattern);

// Colour / area (ShapeLattice::area of the radius) and the area as a float: the horizontal pass's
// input, what shaders/flag/shape_pack.comp writes. color: >= 3 channels; radius_px: 1 channel.
Image flag_shape_pack(const Image& color, const Image& radius_px, const FlagShapeTable& table,
                      int threads = default_cpu_threads());
// The horizontal pass into table.layers() layers (z = |dz| halved, dz + n otherwise), each value
// rounded as `precision` stores it (per-value precisions only: throws std::invalid_argument for the
// bracketed ones). Per pixel, samples left to right, each +colour at its chord's far end and
// -colour past its near end, then accumulated from the top layer down (shaders/flag/horizontal_shape.comp).
FlagLayers flag_shape_horizontal(const Image& packed, const FlagShapeTable& table, const GatherPattern& pattern,
                                 LayerPrecision precision, int threads = default_cpu_threads());
// The same layers summed in the GPU scan binning's order (shaders/flag/horizontal_shape_scan.comp), bit
// for bit (f32; the other per-value precisions round the same f32 values): per row, lattice phase,
// segment of `segment` columns at stride k and layer z, each sample in row order adds itself at the
// start of its row section's interval of output columns (clamped to the segment) and subtracts itself
// past its end, in a difference array; a prefix sum along the segment gives the layer. The same samples
// per layer as flag_shape_horizontal, in another order (within f32 rounding of it). Throws
// std::invalid_argument for bracketed precisions, segment < 1 and an input whose area (.a) is not one
// of the table's.
FlagLayers flag_shape_horizontal_scan(const Image& packed, const FlagShapeTable& table, const GatherPattern& pattern,
                                      LayerPrecision precision, int segment = kFlagScanSegment,
                                      int threads = default_cpu_threads());
// The vertical pass is flag_vertical(layers, pattern, threads, !table.halved).
// How the CPU sums the horizontal pass: by chords (flag_shape_horizontal; the GPU's indexed and masked
// bins) or as the GPU's scan binning does (flag_shape_horizontal_scan).
enum class FlagShapeSums { chords, scan };
// The whole blur: pack, horizontal, vertical. Throws std::invalid_argument for negative colours in an
// unsigned precision and for bracketed precisions.
Image flag_shape_blur(const Image& color, const Image& radius_px, const FlagShapeTable& table,
                      const GatherPattern& pattern, LayerPrecision precision, int threads = default_cpu_threads(),
                      FlagShapeSums sums = FlagShapeSums::chords);

}  // namespace bokeh
