#include "flag_shape.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

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

std::uint64_t FlagShapeTable::bytes_for(const GatherPattern& pattern) {
  const auto side = static_cast<std::uint64_t>(pattern.size_n);
  return side * (side * side + 1) * sizeof(std::int32_t);
}

FlagShapeTable::FlagShapeTable(const Aperture& aperture, const GatherPattern& pattern)
    : lattice(aperture, pattern), half_n(pattern.half()), side(pattern.size_n) {
  halved = flag_layers_halved(aperture, lattice);
  const int n = half_n;
  const std::size_t offsets = static_cast<std::size_t>(side) * side, areas = offsets + 1;
  chords.assign(static_cast<std::size_t>(side) * areas, 0);
  // Offsets in ascending gauge; each group of equal gauges joins at once: for every area m in the
  // group's range the shape is {gauge <= sorted[m - 1]}, i.e. everything up to the group's end.
  std::vector<std::size_t> order(offsets);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lattice.gauge[a] < lattice.gauge[b]; });
  std::vector<int> lo(static_cast<std::size_t>(side), n + 1), hi(static_cast<std::size_t>(side), -n - 1),
      count(static_cast<std::size_t>(side), 0);
  std::size_t group_start = 0;
  while (group_start < offsets) {
    std::size_t group_end = group_start;
    const float g = lattice.gauge[order[group_start]];
    for (; group_end < offsets && lattice.gauge[order[group_end]] == g; ++group_end) {
      const auto at = order[group_end];
      const int column = static_cast<int>(at % side), dz = static_cast<int>(at / side) - n;
      auto c = static_cast<std::size_t>(column);
      lo[c] = std::min(lo[c], dz), hi[c] = std::max(hi[c], dz), ++count[c];
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
    group_start = group_end;
  }
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

Image flag_shape_blur(const Image& color, const Image& radius_px, const FlagShapeTable& table,
                      const GatherPattern& pattern, LayerPrecision precision, int threads) {
  check_layer_input(color, precision);
  const Image packed = flag_shape_pack(color, radius_px, table, threads);
  return flag_vertical(flag_shape_horizontal(packed, table, pattern, precision, threads), pattern, threads, !table.halved);
}

}  // namespace bokeh
