// GPU passes against the CPU references, on small procedural scenes.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "coc.hpp"
#include "coc_tiles_gpu.hpp"
#include "flag.hpp"
#include "flag_config.hpp"
#include "flag_gpu.hpp"
#include "gpu_test_support.hpp"
#include "naive_config.hpp"
#include "naive_gather.hpp"
#include "naive_gpu.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

using test::same_bits;

// Largest per-channel difference relative to the reference's largest value.
double max_rel_error(const Image& a, const Image& ref) {
  double max_ref = 0, max_diff = 0;
  for (std::size_t i = 0; i < ref.pixels.size(); ++i) {
    max_ref = std::max(max_ref, std::abs(double(ref.pixels[i])));
    max_diff = std::max(max_diff, std::abs(double(a.pixels[i]) - ref.pixels[i]));
  }
  return max_diff / max_ref;
}

using test::context;

// A method's defaults (every option of its own present) at this pattern and precision; FLAG through
// its 3D buffer (layer_buffer = full), whose passes these tests check (registers: FlagRegisters).
FilterOptions options_for(const char* method, const GatherPattern& pattern, const std::string& precision) {
  FilterOptions o = find_method(method).defaults(pattern);
  o.precision = precision;
  if (std::string(method) == "flag") o.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::full);
  return o;
}

struct Case {
  const char* scene;
  int size_n, spacing_px;
};

class GpuMatchesCpu : public ::testing::TestWithParam<Case> {};

TEST_P(GpuMatchesCpu, CocPassPacksLikeCpu) {
  const Case c = GetParam();
  const Scene s = make_scene(c.scene, 96, 64);
  const GatherPattern pattern{c.size_n, c.spacing_px};
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * 1.2);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
  auto filter = find_method("naive").make_gpu(frame, options_for("naive", pattern, "f32"));
  vk::TimestampQueries timer(context(), 8);
  gpu::run_frames(frame, *filter, timer);
  const Image gpu_packed = frame.read_packed();
  const CocInput cpu = cpu_coc_pass(s.color, s.depth_m, lens, pattern);
  for (std::size_t i = 0; i < cpu.packed.pixels.size(); ++i)
    ASSERT_NEAR(gpu_packed.pixels[i], cpu.packed.pixels[i], 1e-6f * std::max(1.0f, std::abs(cpu.packed.pixels[i])))
        << "texel " << i / 4 << " channel " << i % 4;
}

TEST_P(GpuMatchesCpu, NaiveAndFlagF32MatchCpuNaive) {
  const Case c = GetParam();
  const Scene s = make_scene(c.scene, 96, 64);
  const GatherPattern pattern{c.size_n, c.spacing_px};
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * 1.2);
  const Image reference = run_cpu(find_method("naive"), s.color, s.depth_m, lens, options_for("naive", pattern, "f32"), 2);
  for (const char* method : {"naive", "flag"}) {
    const Image gpu = run_gpu(context(), find_method(method), s.color, s.depth_m, lens, options_for(method, pattern, "f32"));
    EXPECT_LT(max_rel_error(gpu, reference), 1e-5) << method;
  }
  FilterOptions scan = options_for("flag", pattern, "f32");
  scan.values["horizontal_bins"] = 3;  // "scan"
  EXPECT_LT(max_rel_error(run_gpu(context(), find_method("flag"), s.color, s.depth_m, lens, scan), reference), 1e-5)
      << "flag, scan bins";
}

// Every block of outputs per invocation (gather_block, horizontal_block), the indexed and masked
// binnings of FLAG's horizontal pass (horizontal_bins) and either order of its vertical pass's tiles
// (vertical_order) keep each pixel's order of additions, so on the
// same packed input the GPU gives the strictly ordered CPU references' image bit for bit:
// naive_gather_reference, and for f32 layers flag_blur_reference. The scan binning sums in its own
// order: bit for bit its CPU mirror, flag_horizontal_scan. Run on the packed input the GPU's CoC pass
// wrote (its divisions may round differently from the CPU's).
TEST_P(GpuMatchesCpu, EveryBlockEqualsTheOrderedCpuReferenceBitForBit) {
  const Case c = GetParam();
  const Scene s = make_scene(c.scene, 63, 46);  // partial blocks and workgroups at the right and bottom
  const GatherPattern pattern{c.size_n, c.spacing_px};
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * 1.2);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
  vk::TimestampQueries timer(context(), 16);
  struct Variant {
    const char* method;
    const char* option;
    std::vector<std::string> choices;
  };
  const Variant variants[] = {{"naive", "gather_block", naive_gather_blocks()},
                              {"flag", "horizontal_block", flag_horizontal_blocks()},
                              {"flag", "horizontal_bins", flag_horizontal_bins()},
                              {"flag", "vertical_order", flag_vertical_orders()}};
  for (const Variant& v : variants)
    for (std::size_t choice = 0; choice < v.choices.size(); ++choice) {
      FilterOptions o = options_for(v.method, pattern, "f32");
      o.values[v.option] = static_cast<double>(choice);
      auto filter = find_method(v.method).make_gpu(frame, o);
      gpu::run_frames(frame, *filter, timer);
      const Image packed = frame.read_packed();
      const bool scan = std::string(v.method) == "flag" &&
                        flag_horizontal_binning(flag_config(o).horizontal_bins, context().info(), pattern.layers()) ==
                            FlagHorizontalBins::scan;
      const Image reference =
          std::string(v.method) == "naive" ? naive_gather_reference(packed, pattern, 2)
          : scan ? flag_vertical(flag_horizontal_scan(packed, pattern, LayerPrecision::f32), pattern, 2)
                 : flag_blur_reference(packed, pattern, LayerPrecision::f32, 2);
      EXPECT_TRUE(same_bits(frame.read_output(), reference)) << v.method << " " << v.option << " " << v.choices[choice];
    }
}

// Streamed layers (layer_buffer = streamed): the full buffer's image bit for bit, every precision,
// binning and adaptive, with bands of 1 row (the ring, 2 n k + 1 rows, wraps every few rows), a few
// rows, and auto (one band at this height); and a smaller layer image than the full buffer's.
TEST(FlagStreamed, EqualsTheFullBufferBitForBit) {
  const Scene s = make_scene("hoops", 63, 46);  // partial workgroups at the right and bottom
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{7, 3}}) {
    const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * 1.2);
    gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
    vk::TimestampQueries timer(context(), 16);
    struct Variant {
      std::string precision;
      std::map<std::string, double> values;
      std::vector<int> bands;
    };
    const std::vector<Variant> variants = {{"f32", {}, {1, 5, 0}},
                                           {"f32", {{"horizontal_bins", 1}}, {3}},   // indexed
                                           {"f32", {{"horizontal_bins", 3}}, {3}},   // scan
                                           {"f32", {{"adaptive", 1}}, {2}},
                                           {"f16", {}, {2}},
                                           {"r11g11b10f", {}, {2}},
                                           {"unorm16_bracketed", {}, {2}}};
    for (const Variant& v : variants) {
      FilterOptions o = options_for("flag", pattern, v.precision);
      for (const auto& [key, value] : v.values) o.values[key] = value;
      auto full = find_method("flag").make_gpu(frame, o);
      gpu::run_frames(frame, *full, timer);
      const Image expected = frame.read_output();
      for (int band : v.bands) {
        FilterOptions streamed = o;
        streamed.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::streamed);
        streamed.values["band_rows"] = band;
        auto filter = find_method("flag").make_gpu(frame, streamed);
        const auto passes = gpu::run_frames(frame, *filter, timer);
        EXPECT_EQ(passes.back().pass, "streamed");
        EXPECT_TRUE(same_bits(frame.read_output(), expected))
            << "N " << pattern.size_n << " k " << pattern.spacing_px << " " << v.precision << " band " << band;
        if (band > 0 && band < 10) EXPECT_LT(filter->intermediate_bytes(), full->intermediate_bytes()) << band;
      }
    }
  }
}

// No layer buffer (layer_buffer = registers, shaders/flag/fused.comp): the CPU reference's image bit for
// bit, f32 and f16, and f32 the full buffer's with indexed bins (the same layer values summed in the same
// order); at frame edges, partial workgroups, k = 3, a pattern wider than the frame, and N = 1 and 3 (one
// and three output rows in flight). It allocates no layers, only the tile map's M (tile_max), and stamps
// the fused pass last.
TEST(FlagRegisters, EqualsTheCpuReferenceBitForBit) {
  struct Frame {
    int width_px, height_px;
    GatherPattern pattern;
  };
  for (const Frame& f : {Frame{63, 46, {9, 2}}, Frame{63, 46, {7, 3}}, Frame{70, 52, {41, 2}}, Frame{16, 16, {41, 1}},
                         Frame{40, 30, {1, 1}}, Frame{40, 30, {3, 2}}}) {
    const Scene s = make_scene("hoops", f.width_px, f.height_px);
    const Lens lens = with_max_coc_radius(s.lens, s.depth_m, f.pattern.max_radius_px() * 1.2);
    gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, f.pattern);
    vk::TimestampQueries timer(context(), 16);
    for (const std::string precision : {"f32", "f16"}) {
      SCOPED_TRACE(fmt::format("{}x{} N {} k {} {}", f.width_px, f.height_px, f.pattern.size_n, f.pattern.spacing_px,
                               precision));
      FilterOptions full = options_for("flag", f.pattern, precision);
      full.values["horizontal_bins"] = static_cast<double>(FlagHorizontalBins::indexed);
      auto buffer = find_method("flag").make_gpu(frame, full);
      gpu::run_frames(frame, *buffer, timer);
      const Image expected = frame.read_output();
      for (const auto bins : {FlagHorizontalBins::indexed, FlagHorizontalBins::masked}) {
        SCOPED_TRACE(flag_horizontal_bins()[static_cast<std::size_t>(bins)]);
        FilterOptions registers = full;
        registers.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
        registers.values["horizontal_bins"] = static_cast<double>(bins);
        auto fused = find_method("flag").make_gpu(frame, registers);
        const auto passes = gpu::run_frames(frame, *fused, timer);
        EXPECT_EQ(passes.back().pass, "fused");
        // The map as requested; a driver may round its allocation up (NVIDIA to 64 KiB pages).
        const std::uint64_t map_bytes = gpu::CocTilesGpu::bytes(f.width_px, f.height_px, kFlagFusedTilePx);
        EXPECT_GE(fused->intermediate_bytes(), map_bytes);
        EXPECT_LE(fused->intermediate_bytes(), map_bytes + 65536);
        const Image output = frame.read_output();
        // The CPU reference rounds each f16 layer to nearest, as the registers do; lavapipe's f16 image
        // store rounds toward zero (Vulkan allows either): the buffer within the format's bound of it.
        const LayerPrecision layers = layer_precision_from_string(precision);
        EXPECT_TRUE(same_bits(output, flag_blur_reference(frame.read_packed(), f.pattern, layers, 2)));
        if (layers == LayerPrecision::f32) EXPECT_TRUE(same_bits(output, expected));
        else EXPECT_LE(max_rel_error(output, expected), find_method("flag").gpu_tolerance(registers));
      }
    }
  }
}

// The fused pass's f16 image (layer_buffer = registers, bins as auto chooses unless given) of scene `s`
// with its largest CoC 1.2x the pattern's, beside the CPU reference's image of the same packed input.
struct RegistersRun {
  Image output, reference;
  std::vector<std::string> passes;  // as stamped
};
RegistersRun run_registers_f16(const Scene& s, const GatherPattern& pattern,
                               std::optional<FlagHorizontalBins> bins = std::nullopt) {
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * 1.2);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
  vk::TimestampQueries timer(context(), 16);
  FilterOptions registers = options_for("flag", pattern, "f16");
  registers.values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
  if (bins) registers.values["horizontal_bins"] = static_cast<double>(*bins);
  auto fused = find_method("flag").make_gpu(frame, registers);
  RegistersRun run;
  for (const auto& pass : gpu::run_frames(frame, *fused, timer)) run.passes.push_back(pass.pass);
  run.output = frame.read_output();
  run.reference = flag_blur_reference(frame.read_packed(), pattern, LayerPrecision::f16, 2);
  return run;
}

// The fused pass loads a row's samples only in the windows of columns whose tiles' largest disc can
// reach the workgroup's columns (the tile map's M): in scenes mostly in focus with a few wide discs,
// most windows are left out, and the image stays the CPU reference's bit for bit, for k = 1, 2 and 3
// (a window a tile, two a tile, windows across tiles), masked and indexed bins, and 4 lanes as well
// as 8 where lavapipe runs 128-bit vectors (LP_NATIVE_VECTOR_WIDTH=128). Below 13 layers (N = 21)
// the map is not made and every window is loaded.
TEST(FlagRegisters, LoadsOnlyTheSamplesTheTileMapLetsReachAndKeepsTheImage) {
  for (const std::string scene : {"mostly_in_focus", "points", "half_defocused"})
    for (const GatherPattern pattern : {GatherPattern{81, 2}, GatherPattern{41, 1}, GatherPattern{27, 3},
                                        GatherPattern{21, 2}}) {
      SCOPED_TRACE(fmt::format("{} N {} k {}", scene, pattern.size_n, pattern.spacing_px));
      const RegistersRun run = run_registers_f16(make_scene(scene, 160, 40), pattern);
      const std::vector<std::string> passes =
          flag_fused_reads_tile_map(pattern.layers()) ? std::vector<std::string>{"coc", "tile_max", "fused"}
                                                      : std::vector<std::string>{"coc", "fused"};
      EXPECT_EQ(run.passes, passes);
      EXPECT_TRUE(same_bits(run.output, run.reference));
    }
}

// Indexed bins past 32 layers: a row's first add to each bin is marked in a word of bits a 32 layers
// (fused.comp clears the bins once, not every row); 65 layers use three words, every disc reaching all
// of them. The CPU reference's image bit for bit.
TEST(FlagRegisters, IndexedBinsOfManyLayersEqualTheCpuReference) {
  const RegistersRun run =
      run_registers_f16(make_scene("hoops", 40, 30), GatherPattern{129, 1}, FlagHorizontalBins::indexed);
  EXPECT_EQ(run.passes.back(), "fused");
  EXPECT_TRUE(same_bits(run.output, run.reference));
}

// The registers' f16 rounding (vector arithmetic, not packHalf2x16) at the format's edges, against
// Imath::half in the CPU reference bit for bit: a band of the frame darkened into f16's subnormals and
// flushed zeros, one brightened past its largest value (infinite layers), one left in the normal range.
TEST(FlagRegisters, F16LayersRoundAsTheCpuReferenceAtTheFormatsEdges) {
  Scene s = make_scene("hoops", 72, 48);
  for (int y = 0; y < s.color.height; ++y)
    for (int x = 0; x < s.color.width; ++x)
      for (int c = 0; c < 3; ++c) s.color.px(x, y)[c] *= x < 24 ? 1e-6f : (x < 48 ? 1.0f : 1e6f);
  for (const GatherPattern pattern : {GatherPattern{9, 2}, GatherPattern{41, 2}}) {  // masked and indexed bins
    SCOPED_TRACE(fmt::format("N {}", pattern.size_n));
    const RegistersRun run = run_registers_f16(s, pattern);
    const Image& output = run.output;
    EXPECT_TRUE(same_bits(output, run.reference));
    int subnormal = 0, infinite = 0;  // the edges were reached
    for (const float v : output.pixels) {
      subnormal += v > 0 && v < 6.103515625e-05f;
      infinite += std::isinf(v);
    }
    EXPECT_GT(subnormal, 0);
    EXPECT_GT(infinite, 0);
  }
}

// auto runs registers where it can on a CPU device (lavapipe), any aperture, the full buffer for what
// registers does not run, and the full buffer where no device is named (the models' reference); an explicit
// registers it cannot run is refused with the reason.
TEST(FlagRegisters, AutoChoosesByDeviceAndOptions) {
  const GatherPattern pattern{41, 2};
  FilterOptions o = find_method("flag").defaults(pattern);
  ASSERT_EQ(o.choice<FlagLayerBuffer>("layer_buffer"), FlagLayerBuffer::automatic);
  const vk::DeviceInfo& device = context().info();
  const bool runs = device.is_software() && device.has_subgroup_operations(kFlagScanSubgroupOperations);
  EXPECT_EQ(flag_layer_buffering(o, &device), runs ? FlagLayerBuffer::registers : FlagLayerBuffer::full);
  EXPECT_EQ(flag_layer_buffering(o, nullptr), FlagLayerBuffer::full);
  FilterOptions bracketed = o, reduced = o, adaptive = o, shape = o;
  bracketed.precision = "unorm16_bracketed";
  reduced.buffer_scale = 2;
  adaptive.values["adaptive"] = 1;
  shape.aperture = parse_aperture("blades6");
  // Polygons as the disc, and their memory model with them: no layer buffer where registers run.
  EXPECT_EQ(flag_layer_buffering(shape, &device), runs ? FlagLayerBuffer::registers : FlagLayerBuffer::full);
  vk::Context ctx;
  EXPECT_EQ(find_method("flag").gpu_memory(shape, 800, 600, &ctx).details["layer_buffer_bytes"] == 0, runs);
  EXPECT_GT(find_method("flag").gpu_memory(shape, 800, 600, nullptr).details["layer_buffer_bytes"], 0);
  for (FilterOptions* other : {&bracketed, &reduced, &adaptive}) {
    EXPECT_EQ(flag_layer_buffering(*other, &device), FlagLayerBuffer::full);
    other->values["layer_buffer"] = static_cast<double>(FlagLayerBuffer::registers);
    const std::string why = find_method("flag").unsupported(*other, 64, 48);
    EXPECT_NE(why.find("layer_buffer = registers runs buffer scale 1 with f32 or f16"), std::string::npos) << why;
  }
  // The models follow the device: no layer buffer, one pass of both passes' taps.
  const Method& flag = find_method("flag");
  const FilterOptions as_run = flag.on_device(o, &device);
  const auto work = flag.work(as_run, 800, 600);
  if (runs) {  // the tile map's M, then the fused pass; the map is all it allocates
    ASSERT_EQ(work.size(), 2u);
    EXPECT_EQ(work[0].pass, "tile_max");
    EXPECT_EQ(work[1].pass, "fused");
    EXPECT_EQ(work[1].taps, 2.0 * 800 * 600 * pattern.size_n);
    EXPECT_EQ(flag.gpu_memory(o, 800, 600, &ctx).bytes, gpu::CocTilesGpu::bytes(800, 600, kFlagFusedTilePx));
  }
  EXPECT_EQ(flag.work(o, 800, 600).size(), 2u);  // no device: horizontal and vertical
  EXPECT_GT(flag.gpu_memory(o, 800, 600, nullptr).bytes, 0u);
}

// FLAG with scan bins on the GPU against the vertical pass over its CPU mirror's layers: bit for bit.
bool scan_equals_cpu_mirror(const Scene& s, const GatherPattern& pattern, double coc_scale) {
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px() * coc_scale);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, pattern);
  vk::TimestampQueries timer(context(), 16);
  FilterOptions o = options_for("flag", pattern, "f32");
  o.values["horizontal_bins"] = 3;  // "scan"
  auto filter = find_method("flag").make_gpu(frame, o);
  gpu::run_frames(frame, *filter, timer);
  const Image mirror =
      flag_vertical(flag_horizontal_scan(frame.read_packed(), pattern, LayerPrecision::f32), pattern, 2);
  return same_bits(frame.read_output(), mirror);
}

// The scan binning across segments: frames wider than one segment of kFlagScanSegment columns per
// phase (the last one partial), every phase, samples reaching across segment boundaries.
TEST(FlagScan, EqualsItsCpuMirrorBitForBitAcrossSegments) {
  for (const GatherPattern pattern : {GatherPattern{21, 2}, GatherPattern{9, 3}, GatherPattern{41, 1}}) {
    const Scene s = make_scene("hoops", kFlagScanSegment * pattern.spacing_px + 77, 16);
    EXPECT_TRUE(scan_equals_cpu_mirror(s, pattern, 1.2)) << "N " << pattern.size_n << " k " << pattern.spacing_px;
  }
}

// RGBA16F layers: every stored layer value is a sum of non-negative terms rounded once to half,
// and the output is a sum of such values, so each output channel keeps the relative error of one
// rounding: 2^-11 when rounding to nearest (the CPU emulation), 2^-10 (one ulp) when the driver
// rounds toward zero, which Vulkan permits for float->half conversion (lavapipe does). Plus f32
// summation noise and half's subnormal floor.
TEST_P(GpuMatchesCpu, FlagF16WithinHalfRoundoff) {
  const Case c = GetParam();
  const Scene s = make_scene(c.scene, 96, 64);
  const GatherPattern pattern{c.size_n, c.spacing_px};
  const FilterOptions f16 = options_for("flag", pattern, "f16");
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px());
  const Image reference = run_cpu(find_method("naive"), s.color, s.depth_m, lens, options_for("naive", pattern, "f32"), 2);
  const Image cpu16 = run_cpu(find_method("flag"), s.color, s.depth_m, lens, f16, 2);
  const double round_to_nearest = std::ldexp(1.0, -11), round_toward_zero = std::ldexp(1.0, -10);
  for (const char* bins : {"auto", "scan"}) {
    FilterOptions o = f16;
    o.values["horizontal_bins"] = std::string(bins) == "scan" ? 3 : 0;
    const Image gpu16 = run_gpu(context(), find_method("flag"), s.color, s.depth_m, lens, o);
    for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
      const double ref = std::abs(reference.pixels[i]);
      ASSERT_LE(std::abs(gpu16.pixels[i] - reference.pixels[i]), round_toward_zero * ref * (1 + 1e-3) + 1e-6)
          << "GPU, " << bins << " bins, value " << i;
    }
  }
  for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
    const double ref = std::abs(reference.pixels[i]);
    ASSERT_LE(std::abs(cpu16.pixels[i] - reference.pixels[i]), round_to_nearest * ref * (1 + 1e-3) + 1e-6)
        << "CPU f16 emulation, value " << i;
  }
}

// Extremes a user will hit: they must give finite, bounded results or a failure the harness
// measures, never a crash or a silent NaN.

// A device of this type ("cpu": lavapipe's) for the choices a driver makes by device, with the subgroup
// operations lavapipe and desktop drivers have.
vk::DeviceInfo device_of_type(const char* type) {
  vk::DeviceInfo info;
  info.type = type;
  info.subgroup_operations = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_VOTE_BIT |
                             VK_SUBGROUP_FEATURE_ARITHMETIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT |
                             VK_SUBGROUP_FEATURE_SHUFFLE_BIT;
  return info;
}

// lavapipe computes wrong FLAG layers past a size of the horizontal pass's bins (flag_gpu.cpp): auto
// stays within it, and an explicit block or bracketed precision beyond it is refused there, never run.
TEST(GpuExtremes, FlagStaysWithinWhatLavapipeComputesCorrectly) {
  const vk::DeviceInfo software = device_of_type("cpu"), gpu = device_of_type("discrete");
  FilterOptions o = options_for("flag", GatherPattern{201, 1}, "f32");
  const std::optional<int> automatic = flag_config(o).horizontal_block;  // the option's default
  ASSERT_FALSE(automatic);
  EXPECT_EQ(flag_horizontal_block(automatic, software, 81), 4);
  EXPECT_EQ(flag_horizontal_block(automatic, software, 101), 2);
  EXPECT_EQ(flag_horizontal_block(automatic, software, 200), 1);
  EXPECT_EQ(flag_horizontal_block(automatic, gpu, 101), 1);
  // The bounds are lavapipe's: elsewhere both configurations beyond them are made.
  const bool bounded = context().info().is_software();
  auto expect_refused_if_bounded = [bounded](gpu::GpuFrame& frame, const FilterOptions& options) {
    if (bounded)
      EXPECT_THROW(find_method("flag").make_gpu(frame, options), std::invalid_argument);
    else
      EXPECT_NO_THROW(find_method("flag").make_gpu(frame, options));
  };
  const Scene s = make_scene("points", 48, 40);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, s.lens, o.pattern);
  o.values["horizontal_bins"] = 1;   // "indexed" (auto's scan runs no block)
  o.values["horizontal_block"] = 3;  // "4": 4 x 101 layers
  expect_refused_if_bounded(frame, o);
  o.values["horizontal_block"] = 0;  // auto
  EXPECT_NO_THROW(find_method("flag").make_gpu(frame, o));
  FilterOptions bracketed = options_for("flag", GatherPattern{81, 1}, "unorm10_bracketed");
  gpu::GpuFrame frame81(context(), s.color, s.depth_m, s.lens, bracketed.pattern);
  expect_refused_if_bounded(frame81, bracketed);
}

// The scan's private array is kFlagScanSegment vec3 whatever N (flag_gpu.cpp: lavapipe computed wrong
// layers past ~324 vec3 of the bins): at the largest pattern (N = 201, 101 layers) and single lights
// reaching past the frame, its CPU mirror bit for bit.
TEST(FlagScan, WorksAtTheLargestPattern) {
  EXPECT_TRUE(scan_equals_cpu_mirror(make_scene("points", 48, 40), GatherPattern{201, 1}, 1.0));
}

// horizontal_bins = auto: on CPU devices masked bins up to 12 layers, scan beyond (indexed where the
// device lacks the scan's subgroup ballot and shuffle); indexed on GPUs. An explicit choice is taken
// as it is, and an explicit scan asks the device for those operations.
TEST(FlagBins, AutoIsMaskedThenScanOnCpuDevicesAndIndexedOnGpus) {
  const vk::DeviceInfo software = device_of_type("cpu"), gpu = device_of_type("discrete");
  FilterOptions o = options_for("flag", GatherPattern{41, 2}, "f16");
  auto bins = [&o] { return flag_config(o).horizontal_bins; };
  EXPECT_EQ(flag_horizontal_binning(bins(), software, 12), FlagHorizontalBins::masked);
  EXPECT_EQ(flag_horizontal_binning(bins(), software, 13), FlagHorizontalBins::scan);
  EXPECT_EQ(flag_horizontal_binning(bins(), software, 101), FlagHorizontalBins::scan);
  EXPECT_EQ(flag_horizontal_binning(bins(), gpu, 21), FlagHorizontalBins::indexed);
  EXPECT_EQ(flag_horizontal_binning(bins(), gpu, 81), FlagHorizontalBins::indexed);
  o.values["horizontal_bins"] = 2;  // "masked"
  EXPECT_EQ(flag_horizontal_binning(bins(), gpu, 81), FlagHorizontalBins::masked);
  o.values["horizontal_bins"] = 1;  // "indexed"
  EXPECT_EQ(flag_horizontal_binning(bins(), software, 81), FlagHorizontalBins::indexed);
  o.values["horizontal_bins"] = 3;  // "scan"
  EXPECT_EQ(flag_horizontal_binning(bins(), gpu, 21), FlagHorizontalBins::scan);
  EXPECT_EQ(flag_horizontal_binning(bins(), software, 5), FlagHorizontalBins::scan);
  EXPECT_EQ(find_method("flag").needs(o).subgroup_operations & kFlagScanSubgroupOperations, kFlagScanSubgroupOperations);

  vk::DeviceInfo no_shuffle = software;
  no_shuffle.subgroup_operations &= ~VK_SUBGROUP_FEATURE_SHUFFLE_BIT;
  o.values["horizontal_bins"] = 0;  // "auto"
  EXPECT_EQ(find_method("flag").needs(o).subgroup_operations, 0u);
  EXPECT_EQ(flag_horizontal_binning(bins(), no_shuffle, 12), FlagHorizontalBins::masked);
  EXPECT_EQ(flag_horizontal_binning(bins(), no_shuffle, 13), FlagHorizontalBins::indexed);
}

// The device says which subgroup operations it lacks by name: lavapipe (and desktop drivers) has the
// scan's ballot and shuffle; NVIDIA's partitioned operations it has not.
TEST(FlagBins, TheDeviceNamesTheSubgroupOperationsItLacks) {
  vk::DeviceRequirements scan;
  scan.subgroup_operations = kFlagScanSubgroupOperations;
  EXPECT_TRUE(context().info().has_subgroup_operations(kFlagScanSubgroupOperations));
  EXPECT_EQ(context().unmet(scan), "");
  if (context().info().has_subgroup_operations(VK_SUBGROUP_FEATURE_PARTITIONED_BIT_NV))
    GTEST_SKIP() << "this device has partitioned subgroup operations";
  scan.subgroup_operations |= VK_SUBGROUP_FEATURE_PARTITIONED_BIT_NV;
  EXPECT_EQ(context().unmet(scan), "subgroup operations 0x100 in compute shaders");
}

// The typed configs read every choice as the choice it names: the enums and parsers follow the
// order of the choice lists the options declare.
TEST(MethodConfig, EveryChoiceParsesAsTheOneItNames) {
  FilterOptions flag = options_for("flag", GatherPattern{9, 2}, "r11g11b10f");
  flag.buffer_scale = 2;
  const std::map<std::string, FlagHorizontalBins> bins = {{"auto", FlagHorizontalBins::automatic},
                                                          {"indexed", FlagHorizontalBins::indexed},
                                                          {"masked", FlagHorizontalBins::masked},
                                                          {"scan", FlagHorizontalBins::scan}};
  ASSERT_EQ(flag_horizontal_bins().size(), bins.size());
  for (std::size_t i = 0; i < bins.size(); ++i) {
    flag.values["horizontal_bins"] = static_cast<double>(i);
    EXPECT_EQ(flag_config(flag).horizontal_bins, bins.at(flag_horizontal_bins()[i])) << flag_horizontal_bins()[i];
  }
  for (std::size_t i = 0; i < flag_horizontal_blocks().size(); ++i) {
    const std::string& name = flag_horizontal_blocks()[i];
    flag.values["horizontal_block"] = static_cast<double>(i);
    const std::optional<int> block = flag_config(flag).horizontal_block;
    EXPECT_EQ(block ? std::to_string(*block) : "auto", name);
  }
  const FlagConfig c = flag_config(flag);
  EXPECT_EQ(c.precision, LayerPrecision::r11g11b10f);
  EXPECT_EQ(c.buffer_scale, 2);
  EXPECT_FALSE(c.adaptive);
  flag.values["adaptive"] = 1;  // "on"
  flag.values["adaptive_tile_px"] = 8;
  EXPECT_TRUE(flag_config(flag).adaptive);
  EXPECT_EQ(flag_config(flag).adaptive_tile_px, 8);
  flag.precision = "f8";
  EXPECT_THROW(flag_config(flag), std::invalid_argument);

  FilterOptions naive = find_method("naive").defaults({9, 2});
  for (std::size_t i = 0; i < naive_gather_blocks().size(); ++i) {
    const std::string& name = naive_gather_blocks()[i];
    naive.values["gather_block"] = static_cast<double>(i);
    const std::optional<GatherBlock> block = naive_config(naive).gather_block;
    EXPECT_EQ(block ? std::to_string(block->x) + "x" + std::to_string(block->y) : "auto", name);
  }
}

// An HDR highlight above half-float's largest finite value (65504). f32 layers keep it exactly;
// RGBA16F layers cannot: the driver either saturates (lavapipe rounds toward zero, to 65504) or
// overflows to inf. Either way the loss is visible in the numbers the harness reports.
TEST(GpuExtremes, HdrHighlightBeyondHalfRangeIsMeasuredNotHidden) {
  Image color(32, 24, 3, 0.5f);
  Image depth(32, 24, 1, 3.0f);  // everything in focus: radius 0, output = input in exact arithmetic
  for (int c = 0; c < 3; ++c) color.px(16, 12)[c] = 1e5f;
  const Lens lens;
  const Image f32 = run_gpu(context(), find_method("flag"), color, depth, lens, options_for("flag", {9, 2}, "f32"));
  EXPECT_EQ(f32.px(16, 12)[0], 1e5f);
  const Image f16 = run_gpu(context(), find_method("flag"), color, depth, lens, options_for("flag", {9, 2}, "f16"));
  const float v = f16.px(16, 12)[0];
  EXPECT_FALSE(std::isnan(v));
  EXPECT_TRUE(std::isinf(v) || v <= 65504.0f) << "f16 layers cannot hold 1e5: got " << v;
  // Elsewhere the image is untouched (radius 0: nothing spreads).
  EXPECT_NEAR(f16.px(3, 3)[1], 0.5f, 0.5f * std::ldexp(1.0f, -10));
}

// Near-zero depth makes equation (1) blow up; the CoC pass clamps it to the max radius.
TEST(GpuExtremes, NearZeroDepthClampsToTheMaxRadius) {
  Scene s = make_scene("hoops", 48, 32);
  for (int x = 0; x < 48; ++x) *s.depth_m.px(x, 16) = 1e-7f;
  const GatherPattern pattern{7, 2};
  const Image reference = run_cpu(find_method("naive"), s.color, s.depth_m, s.lens, options_for("naive", pattern, "f32"), 2);
  for (const char* method : {"naive", "flag"}) {
    const Image out = run_gpu(context(), find_method(method), s.color, s.depth_m, s.lens, options_for(method, pattern, "f32"));
    for (float v : out.pixels) ASSERT_TRUE(std::isfinite(v)) << method;
    EXPECT_LT(max_rel_error(out, reference), 1e-5) << method;
  }
}

// Circles far larger than the image: every pixel's disc leaves the frame on all sides.
TEST(GpuExtremes, RadiiLargerThanTheImage) {
  const Scene s = make_scene("pillars", 40, 24);
  const GatherPattern pattern{61, 4};  // max radius 120 px on a 40x24 image
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, pattern.max_radius_px());
  const Image reference = run_cpu(find_method("naive"), s.color, s.depth_m, lens, options_for("naive", pattern, "f32"), 2);
  const Image out = run_gpu(context(), find_method("flag"), s.color, s.depth_m, lens, options_for("flag", pattern, "f32"));
  EXPECT_LT(max_rel_error(out, reference), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Scenes, GpuMatchesCpu,
                         ::testing::Values(Case{"hoops", 9, 2}, Case{"pillars", 7, 3}, Case{"points", 11, 1},
                                           Case{"hoops", 1, 2}),
                         [](const auto& info) {
                           return std::string(info.param.scene) + "_N" + std::to_string(info.param.size_n) + "_k" +
                                  std::to_string(info.param.spacing_px);
                         });

}  // namespace
}  // namespace bokeh
