#include "flag_shape.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "flag_scan.hpp"

namespace bokeh {

namespace {

// Float gauges mirror-exact about the source's row: the shape of every radius is symmetric on the
// lattice, so one half of the layers serves both (its chords are [-h, h]).
bool lattice_mirror_exact(const ShapeLattice& lattice) {
  const int side = lattice.side;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      if (lattice.gauge[static_cast<std::size_t>(j) * side + i] !=
          lattice.gauge[static_cast<std::size_t>(side - 1 - j) * side + i])
        return false;
  return true;
}

}  // namespace

bool flag_layers_halved(const Aperture& aperture, const ShapeLattice& lattice) {
  return aperture.vertically_symmetric() && lattice_mirror_exact(lattice);
}

std::uint64_t FlagShapeTable::bytes_for(const GatherPattern& pattern, int layers, bool scan) {
  const auto side = static_cast<std::uint64_t>(pattern.size_n), areas = side * side + 1;
  const auto groups = static_cast<std::uint64_t>((layers + 7) / 8);
  return (scan ? areas * groups * kSectionInts : side * areas + side) * sizeof(std::int32_t);
}

FlagShapeTable::FlagShapeTable(const Aperture& aperture, const GatherPattern& pattern)
    : FlagShapeTable(aperture, ShapeLattice(aperture, pattern), pattern) {}

FlagShapeTable::FlagShapeTable(const Aperture& aperture, ShapeLattice shape_lattice, const GatherPattern& pattern)
    : lattice(std::move(shape_lattice)), half_n(pattern.half()), side(pattern.size_n) {
  if (lattice.side != side || lattice.gauge.size() != static_cast<std::size_t>(side) * side)
    throw std::invalid_argument(fmt::format("FlagShapeTable: a {}x{} lattice for a pattern of N = {}", lattice.side,
                                            lattice.side, side));
  halved = flag_layers_halved(aperture, lattice);
  const int n = half_n, groups = layer_groups();
  const std::size_t offsets = static_cast<std::size_t>(side) * side, areas = offsets + 1;
  chords.assign(static_cast<std::size_t>(side) * areas + side, 0);  // the chords, then reach
  const std::size_t area_ints = static_cast<std::size_t>(groups) * kSectionInts;
  sections.assign(areas * area_ints, 0);
  // Offsets in ascending gauge; each group of equal gauges joins at once: for every area m in the
  // group's range the shape is {gauge <= sorted[m - 1]}, i.e. everything up to the group's end.
  std::vector<std::size_t> order(offsets);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lattice.gauge[a] < lattice.gauge[b]; });
  // Per lattice column: its chord's extent in rows dz; per row dz + n: its extent in lattice columns.
  std::vector<int> lo(static_cast<std::size_t>(side), n + 1), hi(static_cast<std::size_t>(side), -n - 1),
      count(static_cast<std::size_t>(side), 0);
  std::vector<int> row_lo(static_cast<std::size_t>(side), side), row_hi(static_cast<std::size_t>(side), -1),
      row_count(static_cast<std::size_t>(side), 0);
  std::vector<std::int32_t> area_sections(area_ints);  // this group's shape, for every area it covers
  std::size_t group_start = 0;
  while (group_start < offsets) {
    std::size_t group_end = group_start;
    const float g = lattice.gauge[order[group_start]];
    for (; group_end < offsets && lattice.gauge[order[group_end]] == g; ++group_end) {
      const auto at = order[group_end];
      const int column = static_cast<int>(at % side), dz = static_cast<int>(at / side) - n;
      auto c = static_cast<std::size_t>(column);
      lo[c] = std::min(lo[c], dz), hi[c] = std::max(hi[c], dz), ++count[c];
      auto r = static_cast<std::size_t>(dz + n);
      row_lo[r] = std::min(row_lo[r], column), row_hi[r] = std::max(row_hi[r], column), ++row_count[r];
    }
    for (int column = 0; column < side; ++column) {
      const auto c = static_cast<std::size_t>(column);
      if (count[c] == 0) continue;
      // A convex shape's chord is an interval: FLAG's difference binning needs nothing else.
      if (hi[c] - lo[c] + 1 != count[c])
        throw std::logic_error(fmt::format("FLAG: the aperture {}'s shape on the {}x{} lattice has a gap in column {} "
                                           "(not convex there), which chord extents cannot draw",
                                           aperture.name(), side, side, column - n));
      const std::int32_t packed = (hi[c] + n + 1) << 16 | (lo[c] + n);
      const auto column_chords = chords.begin() + static_cast<std::ptrdiff_t>(c * areas);  // areas group_start + 1 .. group_end
      std::fill(column_chords + static_cast<std::ptrdiff_t>(group_start + 1),
                column_chords + static_cast<std::ptrdiff_t>(group_end + 1), packed);
    }
    // Layer z's row section is row dz = z (halved) or z - n: an interval for a convex shape, which the
    // scan's interval sums need as the chords need theirs.
    std::fill(area_sections.begin(), area_sections.end(), 0);
    for (int z = 0; z < layers(); ++z) {
      const auto r = static_cast<std::size_t>(halved ? z + n : z);
      if (row_count[r] == 0) continue;
      if (row_hi[r] - row_lo[r] + 1 != row_count[r])
        throw std::logic_error(fmt::format("FLAG: the aperture {}'s shape on the {}x{} lattice of area {} has a gap in "
                                           "its row at layer {} (not convex there), which the scan binning's row "
                                           "sections cannot draw",
                                           aperture.name(), side, side, group_end, z));
      std::int32_t* group = area_sections.data() + static_cast<std::size_t>(z / 8) * kSectionInts;
      group[z % 8] = (row_hi[r] + 1) << 16 | row_lo[r];
      // The union of the group's sections (the scan's skip test), packed the same way.
      const int union_lo = group[8] == 0 ? row_lo[r] : std::min(group[8] & 0xffff, row_lo[r]);
      const int union_hi = group[8] == 0 ? row_hi[r] : std::max((group[8] >> 16) - 1, row_hi[r]);
      group[8] = (union_hi + 1) << 16 | union_lo;
    }
    for (std::size_t m = group_start + 1; m <= group_end; ++m)
      std::copy(area_sections.begin(), area_sections.end(),
                sections.begin() + static_cast<std::ptrdiff_t>(m * area_ints));
    group_start = group_end;
  }
  // reach: the first area with a chord in each column, the smallest of it and the columns beyond.
  std::int32_t* reach = chords.data() + static_cast<std::size_t>(side) * areas;
  for (int column = 0; column < side; ++column) {
    std::size_t m = 0;
    while (m < areas && chords[static_cast<std::size_t>(column) * areas + m] == 0) ++m;
    reach[column] = static_cast<std::int32_t>(m);
  }
  for (int d = n - 1; d >= 1; --d)  // from the edges in
    reach[n - d] = std::min(reach[n - d], reach[n - d - 1]), reach[n + d] = std::min(reach[n + d], reach[n + d + 1]);
  reach[n] = 0;
}

int flag_aperture_layers(const Aperture& aperture, const GatherPattern& pattern) {
  if (aperture.is_disc() || flag_layers_halved(aperture, ShapeLattice(aperture, pattern))) return pattern.layers();
  return pattern.size_n;
}

Image flag_shape_pack(const Image& color, const Image& radius_px, const FlagShapeTable& table, int threads) {
  Image packed(color.width, color.height, 4);
  parallel_rows(color.height, threads, [&](int y) {
    for (int x = 0; x < color.width; ++x) {
      const int area = table.lattice.area(*radius_px.px(x, y));
      float* o = packed.px(x, y);
      for (int c = 0; c < 3; ++c) o[c] = color.px(x, y)[c] / static_cast<float>(area);
      o[3] = static_cast<float>(area);
    }
  });
  return packed;
}

FlagLayers flag_shape_horizontal(const Image& packed, const FlagShapeTable& table, const GatherPattern& p,
                                 LayerPrecision precision, int threads) {
  if (is_bracketed(precision))
    throw std::invalid_argument(std::string("FLAG with a non-disc aperture stores per-value precisions only (f32, f16, "
                                            "r11g11b10f), not ") + to_string(precision));
  const int n = p.half(), k = p.spacing_px, w = packed.width, layers = table.layers();
  FlagLayers out{w, packed.height, layers, {}, {}, {}};
  out.rgb.assign(static_cast<std::size_t>(w) * out.height * layers * 3, 0.0f);
  parallel_rows(packed.height, threads, [&](int y) {
    std::vector<float> bins(static_cast<std::size_t>(layers) * 3);
    for (int x = 0; x < w; ++x) {
      std::fill(bins.begin(), bins.end(), 0.0f);
      for (int i = -n; i <= n; ++i) {
        const int sx = x + i * k;
        if (sx < 0 || sx >= w) continue;
        const float* s = packed.px(sx, y);
        // The offset from the source to this pixel is -i k: lattice column n - i.
        const std::int32_t chord = table.chord(n - i, static_cast<int>(s[3]));
        if (chord == 0) continue;
        const int lo = (chord & 0xffff) - n, hi = (chord >> 16) - n - 1;
        float* far = bins.data() + static_cast<std::size_t>(table.halved ? hi : hi + n) * 3;
        for (int c = 0; c < 3; ++c) far[c] += s[c];
        if (table.halved || lo == -n) continue;  // halved: lo = -hi, folded onto |dz|
        float* past = bins.data() + static_cast<std::size_t>(lo - 1 + n) * 3;
        for (int c = 0; c < 3; ++c) past[c] -= s[c];
      }
      float running[3] = {0, 0, 0};
      for (int z = layers - 1; z >= 0; --z) {
        float* dst = out.at(x, y, z);
        for (int c = 0; c < 3; ++c) {
          running[c] += bins[static_cast<std::size_t>(z) * 3 + c];
          dst[c] = round_layer_value(running[c], precision, c);
        }
      }
    }
  });
  return out;
}

FlagLayers flag_shape_horizontal_scan(const Image& packed, const FlagShapeTable& table, const GatherPattern& p,
                                      LayerPrecision precision, int segment, int threads) {
  if (is_bracketed(precision))
    throw std::invalid_argument(std::string("flag_shape_horizontal_scan: ") + to_string(precision) +
                                " is bracketed; a non-disc aperture stores per-value precisions only (f32, f16, "
                                "r11g11b10f)");
  if (segment < 1)
    throw std::invalid_argument(fmt::format("flag_shape_horizontal_scan: segment {} must be >= 1 column", segment));
  if (p.size_n != table.side)
    throw std::invalid_argument(fmt::format("flag_shape_horizontal_scan: a table for N = {} on a pattern of N = {}",
                                            table.side, p.size_n));
  if (packed.channels != 4)
    throw std::invalid_argument(fmt::format("flag_shape_horizontal_scan: the input has {} channels, not 4 (colour / "
                                            "area, area: flag_shape_pack)", packed.channels));
  const int n = p.half(), w = packed.width, layers = table.layers();
  const int max_area = table.side * table.side;
  // The areas index the table: checked here, not in the row workers (an exception there would end the process).
  for (int y = 0; y < packed.height; ++y)
    for (int x = 0; x < w; ++x)
      if (const float a = packed.px(x, y)[3]; !(a >= 0.0f && a <= static_cast<float>(max_area)) || a != std::floor(a))
        throw std::invalid_argument(fmt::format("flag_shape_horizontal_scan: pixel ({}, {}) has area {}, not a whole "
                                                "number of the {}x{} lattice's offsets",
                                                x, y, a, table.side, table.side));
  return flag_scan_layers(packed, p, layers, precision, segment, threads, [&](int y) {
    // Layer z: the output columns t = j + first .. j + last of sample j's row section (offset (t - j) k:
    // lattice column t - j + n), none where the section is 0.
    return [&packed, &table, n, y](int x, int z, int& first, int& last) {
      const std::int32_t section = table.section(static_cast<int>(packed.px(x, y)[3]), z);
      if (section == 0) return false;
      first = (section & 0xffff) - n, last = (section >> 16) - 1 - n;
      return true;
    };
  });
}

Image flag_shape_blur(const Image& color, const Image& radius_px, const FlagShapeTable& table,
                      const GatherPattern& pattern, LayerPrecision precision, int threads, FlagShapeSums sums) {
  check_layer_input(color, precision);
  const Image packed = flag_shape_pack(color, radius_px, table, threads);
  const FlagLayers layers =
      sums == FlagShapeSums::scan
          ? flag_shape_horizontal_scan(packed, table, pattern, precision, kFlagScanSegment, threads)
          : flag_shape_horizontal(packed, table, pattern, precision, threads);
  return flag_vertical(layers, pattern, threads, !table.halved);
}

}  // namespace bokeh
