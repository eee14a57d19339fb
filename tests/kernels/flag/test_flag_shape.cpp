// FLAG for any convex aperture (kernels/flag/flag_shape.hpp, issue 23) against independent truth:
// naive's direct shape test per sample (naive_shape_gather), the light every source conserves, its
// own CPU reference on the GPU, and the driver's allocation against the memory model.
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "aperture.hpp"
#include "coc_tiles_gpu.hpp"
#include "flag.hpp"
#include "flag_gpu.hpp"
#include "flag_shape.hpp"
#include "flag_shape_gpu.hpp"
#include "gpu_test_support.hpp"
#include "method.hpp"
#include "naive_shape.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "test_support.hpp"
#include "vk/memory.hpp"

namespace bokeh {
namespace {

using test::context;

// Every shape issue 23 names, with whether FLAG keeps one half of its layers (mirror-symmetric).
struct Shape {
  const char* name;
  bool halved;
};
constexpr Shape kShapes[] = {{"disc", true},          {"blades5", false},        {"blades5-rot90", true},
                             {"blades6", true},       {"blades7-rot15", false},  {"blades9", false},
                             {"blades6-curv0.5", true}, {"blades7-rot20-curv0.5", false}};

// Random colours and radii over the whole pattern (every area the lattice has, near enough), and a
// black border of `border` px (0: none).
void random_frame(int w, int h, float max_radius_px, unsigned seed, int border, Image& color, Image& radius) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  color = Image(w, h, 3);
  radius = Image(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      *radius.px(x, y) = unit(rng) * max_radius_px;
      const bool inside = x >= border && y >= border && x < w - border && y < h - border;
      for (int c = 0; c < 3; ++c) color.px(x, y)[c] = inside ? unit(rng) * (c == 0 && x % 7 == 0 ? 20.0f : 1.0f) : 0.0f;
    }
}

double largest(const Image& image) {
  double m = 0;
  for (float v : image.pixels) m = std::max(m, static_cast<double>(std::abs(v)));
  return m;
}

// FLAG's defaults through its 3D buffer (layer_buffer = full), whose passes and tables most of these
// tests check; auto runs registers on lavapipe (RegistersEqualTheCpuReferenceBitForBit checks those).
FilterOptions buffer_defaults(const GatherPattern& pattern) {
  FilterOptions o = find_method("flag").defaults(pattern);
  o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::full);
  return o;
}

// The scene's lens drawing `aperture`, fitted so that the largest CoC is `reach` times the pattern's
// largest radius (beyond 1: radii clamped at the pattern's, so every area occurs).
Lens shape_lens(const Scene& s, const GatherPattern& pattern, const Aperture& aperture, double reach = 1.2) {
  Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * reach);
  lens.aperture = aperture;
  return lens;
}

// FLAG's CPU reference and GPU passes on `s` with options `o`, the lens drawing o.aperture.
struct CpuAndGpu {
  Image cpu, gpu;
  std::vector<vk::PassTime> passes;
};
CpuAndGpu run_cpu_and_gpu(const Scene& s, const FilterOptions& o) {
  const Method& flag = find_method("flag");
  const Lens lens = shape_lens(s, o.pattern, o.aperture);
  CpuAndGpu out{run_cpu(flag, s.color, s.depth_m, lens, o, 2), {}, {}};
  out.gpu = run_gpu(context(), flag, s.color, s.depth_m, lens, o, &out.passes);
  return out;
}

// FLAG by chords against naive's shape test on the same float gauges, every shape, f32 and the
// per-value formats: each output sums non-negative layer values (N of them at most) whose own
// rounding is at most 2^-11 (f16) or 2^-6 (r11g11b10f blue) of themselves, so |FLAG - naive| <= that
// fraction of naive's output, plus f32 summation order (the difference bins subtract what they add).
TEST(FlagShape, MatchesNaiveShapeGatherForEveryShape) {
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{15, 1}}) {
    Image color, radius;
    random_frame(53, 41, pattern.max_radius_px(), 7u + pattern.size_n, 0, color, radius);
    for (const Shape& shape : kShapes) {
      SCOPED_TRACE(std::string(shape.name) + " N " + std::to_string(pattern.size_n));
      const Aperture aperture = parse_aperture(shape.name);
      const FlagShapeTable table(aperture, pattern);
      EXPECT_EQ(table.halved, shape.halved);
      EXPECT_EQ(table.layers(), shape.halved ? pattern.layers() : pattern.size_n);
      EXPECT_EQ(flag_aperture_layers(aperture, pattern), table.layers());
      for (bool scan : {false, true})
        EXPECT_EQ(FlagShapeTable::bytes_for(pattern, table.layers(), scan), table.bytes(scan)) << scan;
      const Image naive = naive_shape_gather(color, radius, ShapeLattice(aperture, pattern), pattern, 2);
      const double top = largest(naive);
      for (const auto& [precision, relative] : {std::pair{LayerPrecision::f32, 0.0},
                                                std::pair{LayerPrecision::f16, std::ldexp(1.0, -11)},
                                                std::pair{LayerPrecision::r11g11b10f, std::ldexp(1.0, -6)}}) {
        const Image flag = flag_shape_blur(color, radius, table, pattern, precision, 2);
        for (std::size_t i = 0; i < naive.pixels.size(); ++i)
          ASSERT_NEAR(flag.pixels[i], naive.pixels[i], relative * naive.pixels[i] + 2e-6 * top)
              << to_string(precision) << " value " << i;
      }
    }
  }
}

// A pentagon pointing up (blades5): a light spreads up to its vertex and not as far down; the chord
// of the centre column is [-r, r cos 36] in rows, so it misses dz = 0 for no radius but is asymmetric.
TEST(FlagShape, PentagonPointingUpReachesFurtherUpThanDown) {
  const GatherPattern pattern{15, 1};
  Image color(31, 31, 3), radius(31, 31, 1, 6.5f);
  color.px(15, 15)[1] = 1.0f;
  const Image out = flag_shape_blur(color, radius, FlagShapeTable(parse_aperture("blades5"), pattern), pattern,
                                    LayerPrecision::f32, 1);
  EXPECT_GT(out.px(15, 15 - 6)[1], 0.0f);   // the vertex: 6.5 px up
  EXPECT_EQ(out.px(15, 15 + 6)[1], 0.0f);   // the flat edge: 6.5 cos 36 = 5.26 px down
  EXPECT_GT(out.px(15, 15 + 5)[1], 0.0f);
}

// Energy: away from the border every source's weights sum to one, so a dark-bordered frame's output
// sums to its input, for every shape (f32 layers).
TEST(FlagShape, ConservesEnergyForEveryShape) {
  const GatherPattern pattern{11, 2};
  Image color, radius;
  random_frame(48, 44, pattern.max_radius_px(), 3u, pattern.half() * pattern.spacing_px, color, radius);
  double input = 0;
  for (int y = 0; y < color.height; ++y)
    for (int x = 0; x < color.width; ++x) input += color.px(x, y)[0] + color.px(x, y)[1] + color.px(x, y)[2];
  for (const Shape& shape : kShapes) {
    const Image out = flag_shape_blur(color, radius, FlagShapeTable(parse_aperture(shape.name), pattern), pattern,
                                      LayerPrecision::f32, 2);
    double output = 0;
    for (float v : out.pixels) output += v;
    EXPECT_NEAR(output, input, 1e-5 * input) << shape.name;
  }
}

// The full and the streamed buffer draw every shape with every binning; the other paths say why not,
// naming the option.
TEST(FlagShape, DeclaresItsScope) {
  const Method& flag = find_method("flag");
  FilterOptions o = buffer_defaults({9, 2});
  o.aperture = parse_aperture("blades5");
  EXPECT_EQ(aperture_unsupported(flag, o), "");
  FilterOptions streamed = o;
  streamed.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::streamed);
  EXPECT_EQ(aperture_unsupported(flag, streamed), "");
  for (double bins : {1.0, 2.0, 3.0}) {  // indexed, masked, scan
    FilterOptions v = o;
    v.values["horizontal_bins"] = bins;
    EXPECT_EQ(aperture_unsupported(flag, v), "") << bins;
  }
  FilterOptions adaptive = o;
  adaptive.values["adaptive"] = 1;
  EXPECT_NE(aperture_unsupported(flag, adaptive).find("adaptive = on"), std::string::npos)
      << aperture_unsupported(flag, adaptive);
  FilterOptions bracketed = o, reduced = o;
  bracketed.precision = "unorm10_bracketed";
  reduced.buffer_scale = 2;
  EXPECT_NE(aperture_unsupported(flag, bracketed).find("precision unorm10_bracketed"), std::string::npos);
  EXPECT_NE(aperture_unsupported(flag, reduced).find("buffer scale 2"), std::string::npos);
}

// horizontal_bins = auto for a non-disc aperture: on CPU devices scan from 7 layers on, halved shape or
// both halves, where the device has the scan's subgroup ballot and shuffle, else indexed, never masked;
// indexed on GPUs; an explicit choice as it is. The method's CPU reference and memory model follow it.
TEST(FlagShape, AutoBinsAreScanWhereItWasMeasuredFasterOnCpuDevices) {
  vk::DeviceInfo software, gpu;
  software.type = "cpu";
  software.subgroup_operations = kFlagScanSubgroupOperations;
  gpu.type = "discrete";
  const auto automatic = FlagHorizontalBins::automatic;
  EXPECT_EQ(flag_shape_binning(automatic, software, 6), FlagHorizontalBins::indexed);
  EXPECT_EQ(flag_shape_binning(automatic, software, 7), FlagHorizontalBins::scan);
  EXPECT_EQ(flag_shape_binning(automatic, software, 153), FlagHorizontalBins::scan);
  EXPECT_EQ(flag_shape_binning(automatic, gpu, 77), FlagHorizontalBins::indexed);
  EXPECT_EQ(flag_shape_binning(FlagHorizontalBins::masked, software, 77), FlagHorizontalBins::masked);
  EXPECT_EQ(flag_shape_binning(FlagHorizontalBins::scan, gpu, 5), FlagHorizontalBins::scan);
  vk::DeviceInfo no_ballot = software;  // the scan's lanes hand samples on with ballot and shuffle
  no_ballot.subgroup_operations = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_SHUFFLE_BIT;
  EXPECT_EQ(flag_shape_binning(automatic, no_ballot, 77), FlagHorizontalBins::indexed);
  // Without a device the model takes lavapipe's choice: N = 13 halves the hexagon into 7 layers.
  const Method& flag = find_method("flag");
  for (const auto& [name, n, table] : {std::tuple{"blades6", 11, "chords"}, std::tuple{"blades6", 13, "row sections"},
                                       std::tuple{"blades5", 5, "chords"}, std::tuple{"blades5", 7, "row sections"}}) {
    FilterOptions o = buffer_defaults({n, 2});
    o.aperture = parse_aperture(name);
    EXPECT_EQ(flag.gpu_memory(o, 64, 48, nullptr).details["horizontal_table"], table) << name << " N " << n;
  }
}

// The chord table's reach against the lattice itself: a source of area m (its shape the offsets whose
// gauge is at most the m-th smallest) holds an offset in lattice column c or beyond it (away from the
// centre) exactly when m >= reach(c), so the fused pass's skip drops only samples without a chord.
TEST(FlagShape, ReachIsTheFirstAreaHoldingTheColumnOrBeyond) {
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{15, 1}, GatherPattern{41, 2}})
    for (const Shape& shape : kShapes) {
      SCOPED_TRACE(std::string(shape.name) + " N " + std::to_string(pattern.size_n));
      const FlagShapeTable table(parse_aperture(shape.name), pattern);
      const int n = pattern.half(), side = pattern.size_n;
      EXPECT_EQ(table.reach(n), 0);
      for (int c = 0; c < side; ++c)
        for (int m = 1; m <= side * side; ++m) {
          const float within = table.lattice.sorted[static_cast<std::size_t>(m) - 1];
          bool holds = false;
          for (int j = 0; j < side && !holds; ++j)
            for (int c2 = 0; c2 < side && !holds; ++c2)
              holds = (c < n ? c2 <= c : c > n ? c2 >= c : true) &&
                      table.lattice.gauge[static_cast<std::size_t>(j) * side + c2] <= within;
          ASSERT_EQ(m >= table.reach(c), holds) << "column " << c - n << " area " << m;
        }
    }
}

// The row sections against the chords they come from: for every area and layer, lattice column c is
// in the section exactly when its chord covers the layer (halved: hi >= z; both halves: lo <= z - n
// <= hi), and each group's union is the hull of its sections.
TEST(FlagShape, RowSectionsAreTheColumnsWhoseChordsCoverTheLayer) {
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{15, 1}})
    for (const Shape& shape : kShapes) {
      SCOPED_TRACE(std::string(shape.name) + " N " + std::to_string(pattern.size_n));
      const FlagShapeTable table(parse_aperture(shape.name), pattern);
      const int n = pattern.half(), side = pattern.size_n;
      for (int m = 0; m <= side * side; ++m)
        for (int g = 0; g < table.layer_groups(); ++g) {
          int union_lo = side, union_hi = -1;
          for (int z = 8 * g; z < 8 * g + 8; ++z) {
            if (z >= table.layers()) {
              ASSERT_EQ(table.sections[(static_cast<std::size_t>(m) * table.layer_groups() + g) *
                                           FlagShapeTable::kSectionInts + z % 8], 0);
              continue;
            }
            const std::int32_t section = table.section(m, z);
            const int a = section & 0xffff, b = (section >> 16) - 1;
            for (int c = 0; c < side; ++c) {
              const std::int32_t chord = table.chord(c, m);
              const int lo = (chord & 0xffff) - n, hi = (chord >> 16) - n - 1;
              const bool covers = chord != 0 && (table.halved ? hi >= z : lo <= z - n && z - n <= hi);
              ASSERT_EQ(covers, section != 0 && a <= c && c <= b) << "area " << m << " layer " << z << " column " << c;
            }
            if (section != 0) union_lo = std::min(union_lo, a), union_hi = std::max(union_hi, b);
          }
          const std::int32_t hull = table.section_union(m, g);
          EXPECT_EQ(hull, union_hi < 0 ? 0 : (union_hi + 1) << 16 | union_lo) << "area " << m << " group " << g;
        }
    }
}

// A lattice whose columns are intervals but one of whose rows is not (a U: the centre row, then two
// arms above it, then square rings): the chords would draw it, the scan's row sections cannot, and the
// table says so; with the U's gap filled it is accepted.
TEST(FlagShape, RowSectionWithAGapIsRefused) {
  const GatherPattern pattern{5, 1};
  const Aperture aperture = parse_aperture("blades5");
  ShapeLattice u(aperture, pattern);
  const int side = u.side, n = pattern.half();
  auto at = [&](int column, int row) -> float& { return u.gauge[static_cast<std::size_t>(row) * side + column]; };
  for (int row = 0; row < side; ++row)
    for (int column = 0; column < side; ++column)
      at(column, row) = 10.0f + static_cast<float>(std::max(std::abs(column - n), std::abs(row - n)));
  at(2, 2) = 0.0f;
  at(1, 2) = at(3, 2) = 1.0f;  // the centre row: columns 1..3
  at(1, 1) = at(3, 1) = 2.0f;  // the arms one row up: columns 1 and 3, not 2 (area 5)
  auto table_of = [&] {
    u.sorted = u.gauge;
    std::sort(u.sorted.begin(), u.sorted.end());
    return FlagShapeTable(aperture, u, pattern);
  };
  try {
    table_of();
    FAIL() << "no error";
  } catch (const std::logic_error& e) {
    const std::string what = e.what();
    for (const char* words : {"blades5", "5x5", "area 5", "layer 1", "row"})
      EXPECT_NE(what.find(words), std::string::npos) << words << ": " << what;
  }
  at(2, 1) = 2.0f;  // the U filled: two whole rows, convex
  EXPECT_NO_THROW(table_of());
}

// The scan's order of additions (flag_shape_horizontal_scan, the GPU's) against the chords' (flag_shape_horizontal):
// the same samples per layer, so the same layers to f32 rounding, 1e-5 of the largest layer value,
// every shape, segments of 1 column, a few, and the GPU's; the per-value formats round the same values.
TEST(FlagShape, ScanLayersMatchTheChordLayersToRounding) {
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{15, 1}}) {
    Image color, radius;
    random_frame(61, 23, pattern.max_radius_px(), 11u + pattern.size_n, 0, color, radius);
    for (const Shape& shape : kShapes) {
      if (std::string(shape.name) == "disc") continue;
      const FlagShapeTable table(parse_aperture(shape.name), pattern);
      const Image packed = flag_shape_pack(color, radius, table, 2);
      const FlagLayers chords = flag_shape_horizontal(packed, table, pattern, LayerPrecision::f32, 2);
      double top = 0;
      for (float v : chords.rgb) top = std::max(top, static_cast<double>(std::abs(v)));
      for (int segment : {1, 5, kFlagScanSegment}) {
        SCOPED_TRACE(std::string(shape.name) + " N " + std::to_string(pattern.size_n) + " segment " +
                     std::to_string(segment));
        const FlagLayers scan = flag_shape_horizontal_scan(packed, table, pattern, LayerPrecision::f32, segment, 2);
        ASSERT_EQ(scan.layers, chords.layers);
        ASSERT_EQ(scan.rgb.size(), chords.rgb.size());
        for (std::size_t i = 0; i < scan.rgb.size(); ++i)
          ASSERT_NEAR(scan.rgb[i], chords.rgb[i], 1e-5 * top) << "value " << i;
      }
      const FlagLayers f16 = flag_shape_horizontal_scan(packed, table, pattern, LayerPrecision::f16, 7, 2);
      const FlagLayers f32 = flag_shape_horizontal_scan(packed, table, pattern, LayerPrecision::f32, 7, 2);
      for (std::size_t i = 0; i < f16.rgb.size(); ++i)
        ASSERT_EQ(f16.rgb[i], round_layer_value(f32.rgb[i], LayerPrecision::f16, static_cast<int>(i % 3)));
      // The whole blur by either sum.
      const Image by_chords = flag_shape_blur(color, radius, table, pattern, LayerPrecision::f32, 2);
      const Image by_scan =
          flag_shape_blur(color, radius, table, pattern, LayerPrecision::f32, 2, FlagShapeSums::scan);
      const double out_top = largest(by_chords);
      for (std::size_t i = 0; i < by_chords.pixels.size(); ++i)
        ASSERT_NEAR(by_scan.pixels[i], by_chords.pixels[i], 1e-5 * out_top) << shape.name << " output " << i;
    }
  }
}

TEST(FlagShape, ScanRefusesBadInput) {
  const GatherPattern pattern{9, 2};
  const FlagShapeTable table(parse_aperture("blades5"), pattern);
  Image color, radius;
  random_frame(20, 6, pattern.max_radius_px(), 5u, 0, color, radius);
  Image packed = flag_shape_pack(color, radius, table, 1);
  EXPECT_THROW(flag_shape_horizontal_scan(packed, table, pattern, LayerPrecision::unorm16_bracketed),
               std::invalid_argument);
  EXPECT_THROW(flag_shape_horizontal_scan(packed, table, pattern, LayerPrecision::f32, 0), std::invalid_argument);
  EXPECT_THROW(flag_shape_horizontal_scan(packed, table, GatherPattern{11, 2}, LayerPrecision::f32),
               std::invalid_argument);
  EXPECT_THROW(flag_shape_horizontal_scan(color, table, pattern, LayerPrecision::f32), std::invalid_argument);
  for (float area : {-1.0f, 2.5f, 82.0f, std::nanf("")}) {
    Image bad = packed;
    bad.px(7, 3)[3] = area;
    try {
      flag_shape_horizontal_scan(bad, table, pattern, LayerPrecision::f32, kFlagScanSegment, 2);
      ADD_FAILURE() << "area " << area << ": no error";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("pixel (7, 3)"), std::string::npos) << e.what();
    }
  }
}

// The memory model: both halves for the asymmetric pentagon, one for the hexagon (1080p, N = 41, f16),
// and the bytes the GPU driver allocates for a shape equal the model's (as the disc's do), with the
// chord table (indexed, masked) or the row sections (scan).
TEST(FlagShape, MemoryModelDeclaresBothHalvesAndMatchesTheDriver) {
  const Method& flag = find_method("flag");
  FilterOptions hexagon = buffer_defaults({41, 1}), pentagon = hexagon;
  hexagon.aperture = parse_aperture("blades6");
  pentagon.aperture = parse_aperture("blades5");
  const std::uint64_t texels = 1920ull * 1080 * 8;
  EXPECT_EQ(flag.gpu_memory(hexagon, 1920, 1080, nullptr).details["layer_buffer_bytes"], texels * 21);
  EXPECT_EQ(flag.gpu_memory(pentagon, 1920, 1080, nullptr).details["layer_buffer_bytes"], texels * 41);
  EXPECT_EQ(flag.gpu_memory(buffer_defaults({41, 1}), 1920, 1080, nullptr).details["texel_bytes"], texels * 21);
  FilterOptions scan = pentagon, indexed = pentagon;
  scan.values["horizontal_bins"] = 3;
  indexed.values["horizontal_bins"] = 1;
  const MemoryUse indexed_model = flag.gpu_memory(indexed, 1920, 1080, nullptr);
  const MemoryUse scan_model = flag.gpu_memory(scan, 1920, 1080, nullptr);
  EXPECT_EQ(scan_model.details["horizontal_table"], "row sections");
  // 41 layers: 6 groups of 48 bytes per area, against 41 columns of 4 bytes and the chords' reach
  // (an int a column).
  EXPECT_EQ(scan_model.bytes - indexed_model.bytes, (41ull * 41 + 1) * (6 * 48 - 41 * 4) - 41 * 4);

  const Scene s = make_scene("hoops", 61, 45);
  for (const char* name : {"blades5", "blades6"})
    for (double bins : {1.0, 3.0}) {  // indexed, scan
      FilterOptions o = buffer_defaults({9, 2});
      o.aperture = parse_aperture(name);
      o.values["horizontal_bins"] = bins;
      Lens lens = s.lens;
      lens.aperture = o.aperture;
      gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, o.pattern);
      const auto filter = flag.make_gpu(frame, o);
      const MemoryUse model = flag.gpu_memory(o, 61, 45, &context());
      EXPECT_TRUE(model.from_driver);
      EXPECT_EQ(model.details["horizontal_table"], bins == 3.0 ? "row sections" : "chords");
      EXPECT_EQ(model.details["layer_buffer_bytes"].get<std::uint64_t>(),
                vk::image_3d_requirement_bytes(context(), layer_format(LayerPrecision::f16), 61, 45,
                                               std::string(name) == "blades5" ? 9 : 5));
      // Buffers are sub-allocated at the device's alignment: within a few hundred bytes each.
      EXPECT_GE(filter->intermediate_bytes(), model.bytes) << name << " bins " << bins;
      EXPECT_LE(filter->intermediate_bytes(), model.bytes + 3 * 256) << name << " bins " << bins;
    }
  // In registers: no layers, the chord table and the fused pass's map of areas (made whether or not it
  // is read), which its pass tile_max fills from 15 layers on; the driver's bytes as the model's.
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{41, 2}}) {
    FilterOptions o = buffer_defaults(pattern);
    o.aperture = parse_aperture("blades6");
    o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
    Lens lens = s.lens;
    lens.aperture = o.aperture;
    gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, o.pattern);
    const auto filter = flag.make_gpu(frame, o);
    const MemoryUse model = flag.gpu_memory(o, 61, 45, &context());
    EXPECT_EQ(model.details["layer_buffer_bytes"], 0);
    EXPECT_EQ(model.details["tile_map_bytes"], gpu::CocTilesGpu::bytes(61, 45, kFlagFusedTilePx));
    EXPECT_GE(filter->intermediate_bytes(), model.bytes) << pattern.size_n;
    EXPECT_LE(filter->intermediate_bytes(), model.bytes + 4 * 256) << pattern.size_n;
    std::vector<std::string> passes;
    for (const PassWork& p : flag.work(o, 61, 45)) passes.push_back(p.pass);
    const std::vector<std::string> modelled = pattern.size_n == 41
                                                  ? std::vector<std::string>{"shape_pack", "tile_max", "fused"}
                                                  : std::vector<std::string>{"shape_pack", "fused"};
    EXPECT_EQ(passes, modelled);
  }
}

// The GPU against the CPU reference, every per-value precision, horizontal block and the scan binning,
// asymmetric, symmetric and curved shapes, within the method's declared bound.
TEST(FlagShape, GpuMatchesCpuReference) {
  const Method& flag = find_method("flag");
  const Scene s = make_scene("hoops", 63, 46);
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{15, 1}})
    for (const char* name : {"blades5", "blades6", "blades7-rot15-curv0.3"})
      for (const char* precision : {"f32", "f16", "r11g11b10f"})
        // Auto (block 4 on lavapipe), block 1 (f32 only: the same layers either way), scan bins (the
        // CPU reference then sums in the scan's order).
        for (const auto& [block, bins] : {std::pair{0.0, 0.0}, std::pair{1.0, 0.0}, std::pair{0.0, 3.0}}) {
          if (block == 1.0 && std::string(precision) != "f32") continue;
          SCOPED_TRACE(std::string(name) + " " + precision + " N " + std::to_string(pattern.size_n) + " bins " +
                       flag_horizontal_bins()[std::size_t(bins)]);
          FilterOptions o = buffer_defaults(pattern);
          o.precision = precision;
          o.aperture = parse_aperture(name);
          o.values["horizontal_block"] = block;
          o.values["horizontal_bins"] = bins;
          const auto [cpu, gpu, passes] = run_cpu_and_gpu(s, o);
          ASSERT_EQ(passes.size(), 4u);
          EXPECT_EQ(passes[1].pass, "shape_pack");
          double diff = 0;
          for (std::size_t i = 0; i < cpu.pixels.size(); ++i)
            diff = std::max(diff, static_cast<double>(std::abs(gpu.pixels[i] - cpu.pixels[i])));
          EXPECT_LE(diff / largest(cpu), flag.gpu_tolerance(o));
        }
}

// layer_buffer = registers for a polygon (shaders/flag/fused.comp with SHAPE, asked for explicitly):
// the CPU reference's image bit for bit (f32 and f16: the same chords and layer values, each rounded to
// nearest, summed in the same order), halved shapes and both halves, indexed and masked bins (41 layers
// of blades5 at N = 41: the indexed bins' row marks in a second word); and no layer buffer, one fused
// pass after shape_pack (and the map of areas, tile_max, where it is read).
TEST(FlagShape, RegistersEqualTheCpuReferenceBitForBit) {
  const Method& flag = find_method("flag");
  const Scene s = make_scene("hoops", 63, 46);
  for (const GatherPattern pattern :
       {GatherPattern{9, 2}, GatherPattern{15, 1}, GatherPattern{7, 3}, GatherPattern{41, 1}})
    for (const char* name : {"blades5", "blades6", "blades7-rot15-curv0.3"})
      for (const char* precision : {"f32", "f16"})
        for (const auto bins : {FlagHorizontalBins::indexed, FlagHorizontalBins::masked}) {
          SCOPED_TRACE(std::string(name) + " " + precision + " N " + std::to_string(pattern.size_n) + " k " +
                       std::to_string(pattern.spacing_px) + " " + flag_horizontal_bins()[std::size_t(bins)]);
          FilterOptions o = flag.defaults(pattern);
          o.precision = precision;
          o.aperture = parse_aperture(name);
          o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
          o.values["horizontal_bins"] = static_cast<double>(bins);
          ASSERT_EQ(flag.unsupported(o, 63, 46), "");
          const auto [cpu, gpu, passes] = run_cpu_and_gpu(s, o);
          const bool map = flag_fused_reads_tile_map(pattern.layers(), true);
          ASSERT_EQ(passes.size(), map ? 4u : 3u);
          EXPECT_EQ(passes[1].pass, "shape_pack");
          if (map) EXPECT_EQ(passes[2].pass, "tile_max");
          EXPECT_EQ(passes.back().pass, "fused");
          EXPECT_TRUE(test::same_bits(gpu, cpu));
        }
  FilterOptions o = flag.defaults({41, 2});
  o.aperture = parse_aperture("blades5");
  o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
  EXPECT_EQ(flag.gpu_memory(o, 800, 600, nullptr).details["layer_buffer_bytes"], 0);
  // A polygon asked for in registers at a precision they do not run: refused with the reason.
  FilterOptions r11 = o;
  r11.pattern = {9, 2};
  r11.precision = "r11g11b10f";
  const Lens lens = shape_lens(s, r11.pattern, r11.aperture);
  EXPECT_THROW(run_gpu(context(), flag, s.color, s.depth_m, lens, r11), std::invalid_argument);
}

// A polygon's fused pass loads a row's samples only in the windows whose tiles' largest area reaches
// the workgroup's nearest column (the map of shape_pack's areas against the chord table's reach): in
// scenes mostly in focus most windows are left out, and the image stays the full buffer's with indexed
// bins (f32: the same layer values summed in the same order) and the CPU reference's with the same bins,
// bit for bit, for k = 1, 2 and 3, a halved shape (blades6) and both halves (blades5), masked and indexed
// bins; and with the defaults (f16, auto) the CPU reference's, which sums by chords as lavapipe's
// registers do. Below 15 layers (N = 21) the map is not made and every window is loaded.
TEST(FlagShape, RegistersLoadOnlyTheSamplesTheAreaMapLetsReach) {
  const Method& flag = find_method("flag");
  for (const std::string scene : {"mostly_in_focus", "points", "half_defocused"})
    for (const GatherPattern pattern : {GatherPattern{81, 2}, GatherPattern{41, 1}, GatherPattern{33, 3},
                                        GatherPattern{21, 2}})
      for (const char* name : {"blades5", "blades6"}) {
        const Scene s = make_scene(scene, 160, 40);
        FilterOptions full = flag.defaults(pattern);
        full.precision = "f32";
        full.aperture = parse_aperture(name);
        full.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::full);
        full.values["horizontal_bins"] = static_cast<double>(FlagHorizontalBins::indexed);
        const Lens lens = shape_lens(s, pattern, full.aperture);
        const Image expected = run_gpu(context(), flag, s.color, s.depth_m, lens, full);
        for (const auto bins : {FlagHorizontalBins::indexed, FlagHorizontalBins::masked}) {
          SCOPED_TRACE(fmt::format("{} N {} k {} {} {}", scene, pattern.size_n, pattern.spacing_px, name,
                                   flag_horizontal_bins()[static_cast<std::size_t>(bins)]));
          FilterOptions registers = full;
          registers.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
          registers.values["horizontal_bins"] = static_cast<double>(bins);
          std::vector<vk::PassTime> passes;
          const Image output = run_gpu(context(), flag, s.color, s.depth_m, lens, registers, &passes);
          std::vector<std::string> names;
          for (const auto& p : passes) names.push_back(p.pass);
          const std::vector<std::string> stamped =
              flag_fused_reads_tile_map(pattern.layers(), true) ? std::vector<std::string>{"coc", "shape_pack", "tile_max", "fused"}
                                                          : std::vector<std::string>{"coc", "shape_pack", "fused"};
          EXPECT_EQ(names, stamped);
          EXPECT_TRUE(test::same_bits(output, expected));
          EXPECT_TRUE(test::same_bits(output, run_cpu(flag, s.color, s.depth_m, lens, registers, 2)));
        }
        // The defaults as a user runs them (f16, auto: registers on lavapipe, bins as it picks), the CPU
        // reference summing as lavapipe does.
        FilterOptions defaults = flag.defaults(pattern);
        defaults.aperture = full.aperture;
        EXPECT_TRUE(test::same_bits(run_gpu(context(), flag, s.color, s.depth_m, lens, defaults),
                                    run_cpu(flag, s.color, s.depth_m, lens, defaults, 2)))
            << scene << " N " << pattern.size_n << " " << name << " defaults";
      }
}

// Masked bins (a compare per bin instead of an indexed add) add the same values to the same bins: the
// indexed bins' image bit for bit, both halves or one, every horizontal block.
TEST(FlagShape, MaskedBinsMatchIndexedBitForBit) {
  const Method& flag = find_method("flag");
  const Scene s = make_scene("hoops", 61, 47);
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{15, 1}})
    for (const char* name : {"blades5", "blades6", "blades7-rot15-curv0.3"}) {
      SCOPED_TRACE(std::string(name) + " N " + std::to_string(pattern.size_n));
      const Lens lens = shape_lens(s, pattern, parse_aperture(name));
      gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
      vk::TimestampQueries timer(context(), 16);
      FilterOptions o = buffer_defaults(pattern);
      o.precision = "f32";
      o.aperture = lens.aperture;
      o.values["horizontal_bins"] = 1;  // indexed
      auto indexed = flag.make_gpu(frame, o);
      gpu::run_frames(frame, *indexed, timer);
      const Image expected = frame.read_output();
      for (double block : {0.0, 1.0}) {
        o.values["horizontal_bins"] = 2;  // masked
        o.values["horizontal_block"] = block;
        auto masked = flag.make_gpu(frame, o);
        gpu::run_frames(frame, *masked, timer);
        EXPECT_EQ(frame.read_output().pixels, expected.pixels) << "block " << block;
      }
    }
}

// Streamed layers (a ring of B + 2 n k rows, band by band) give the full buffer's image bit for bit,
// both halves or one, chords or scan, in less memory; the model sizes the ring as the driver allocates it.
TEST(FlagShape, StreamedLayersMatchTheFullBufferBitForBit) {
  const Method& flag = find_method("flag");
  const Scene s = make_scene("hoops", 61, 47);
  const GatherPattern pattern{9, 2};
  for (const char* name : {"blades5", "blades6"})
    for (const auto& [precision, bins] : {std::pair{"f32", 0.0}, std::pair{"f16", 0.0}, std::pair{"f32", 3.0}}) {
      SCOPED_TRACE(std::string(name) + " " + precision + " bins " + flag_horizontal_bins()[std::size_t(bins)]);
      FilterOptions o = buffer_defaults(pattern);
      o.precision = precision;
      o.aperture = parse_aperture(name);
      o.values["horizontal_bins"] = bins;
      const Lens lens = shape_lens(s, pattern, o.aperture);
      gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
      vk::TimestampQueries timer(context(), 16);
      auto full = flag.make_gpu(frame, o);
      gpu::run_frames(frame, *full, timer);
      const Image expected = frame.read_output();
      for (int band : {1, 5, 0}) {
        FilterOptions streamed = o;
        streamed.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::streamed);
        streamed.values["band_rows"] = band;
        auto filter = flag.make_gpu(frame, streamed);
        const auto passes = gpu::run_frames(frame, *filter, timer);
        EXPECT_EQ(passes.back().pass, "streamed");
        const Image got = frame.read_output();
        EXPECT_EQ(got.pixels, expected.pixels) << "band " << band;
        const MemoryUse model = flag.gpu_memory(streamed, 61, 47, &context());
        EXPECT_GE(filter->intermediate_bytes(), model.bytes) << band;
        EXPECT_LE(filter->intermediate_bytes(), model.bytes + 3 * 256) << band;
        if (band == 1 || band == 5) {
          EXPECT_EQ(model.details["extent"]["height"], band + 2 * pattern.half() * pattern.spacing_px);
          EXPECT_LT(filter->intermediate_bytes(), full->intermediate_bytes()) << band;
        }
      }
    }
}

// The scan binning's CPU mirror (flag_shape_horizontal_scan, then flag_vertical, f32) of the frame the GPU
// just ran: its weights from the GPU's radii (colour / area, an exact division on both).
Image scan_mirror(gpu::GpuFrame& frame, const Image& color, const Aperture& aperture, const GatherPattern& pattern) {
  const Image packed = frame.read_packed();
  Image radius(packed.width, packed.height, 1);
  for (std::size_t i = 0; i < packed.pixel_count(); ++i) radius.pixels[i] = packed.pixels[i * 4 + 3];
  const FlagShapeTable table(aperture, pattern);
  const Image weighted = flag_shape_pack(color, radius, table, 2);
  return flag_vertical(flag_shape_horizontal_scan(weighted, table, pattern, LayerPrecision::f32), pattern, 2,
                       !table.halved);
}

// The scan binning (f32) of `aperture` on the GPU against its CPU mirror (scan_mirror), bit for bit, the
// lens fitted so that the scene's largest CoC is `reach` times the pattern's largest radius (beyond 1:
// radii clamped at the pattern's, every area).
void expect_scan_equals_its_mirror(const Scene& s, const GatherPattern& pattern, const char* aperture, double reach) {
  const Method& flag = find_method("flag");
  FilterOptions o = buffer_defaults(pattern);
  o.precision = "f32";
  o.aperture = parse_aperture(aperture);
  o.values["horizontal_bins"] = 3;  // scan
  const Lens lens = shape_lens(s, pattern, o.aperture, reach);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
  vk::TimestampQueries timer(context(), 16);
  auto filter = flag.make_gpu(frame, o);
  gpu::run_frames(frame, *filter, timer);
  const Image gpu = frame.read_output();
  EXPECT_GT(largest(gpu), 0.0);
  EXPECT_TRUE(test::same_bits(gpu, scan_mirror(frame, s.color, o.aperture, pattern)));
}

// The halved hexagon and the asymmetric pentagon, k = 1 and 2, on frames wider than one segment of
// kFlagScanSegment columns per phase (the last one partial), so the patterns reach across segment
// boundaries.
TEST(FlagShape, ScanEqualsItsCpuMirrorBitForBitAcrossSegments) {
  for (const GatherPattern pattern : {GatherPattern{21, 2}, GatherPattern{41, 1}})
    for (const char* name : {"blades6", "blades5"}) {
      SCOPED_TRACE(std::string(name) + " N " + std::to_string(pattern.size_n) + " k " +
                   std::to_string(pattern.spacing_px));
      expect_scan_equals_its_mirror(make_scene("hoops", kFlagScanSegment * pattern.spacing_px + 77, 16), pattern,
                                    name, 1.2);
    }
}

// The largest pattern (N = 201: the pentagon's 201 layers in 26 groups, a 50 MB row-section table) with
// single lights reaching past the frame: the CPU mirror bit for bit.
TEST(FlagShape, ScanWorksAtTheLargestPattern) {
  expect_scan_equals_its_mirror(make_scene("points", 48, 40), GatherPattern{201, 1}, "blades5", 1.0);
}

}  // namespace
}  // namespace bokeh
