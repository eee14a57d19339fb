// The adaptive mode of naive and FLAG (method option adaptive = on; kernels/core/coc_tiles.hpp).
// Checked against independent truth:
//   the tile map against brute force over every source and pixel (no source missed);
//   the GPU tile map against the CPU one, integer for integer;
//   adaptive against worst-case output: naive bit for bit; FLAG bit for bit (f32) and, with stored
//   layer formats, bit for bit wherever something blurred reaches the tile, within one rounding of
//   the format where the tile passes its input through (adaptive gives the input exactly, the
//   worst case its round trip through one layer);
//   the layers allocated against the scene's largest radius (closed form) and the driver's sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "coc.hpp"
#include "coc_tiles.hpp"
#include "coc_tiles_gpu.hpp"
#include "flag.hpp"
#include "flag_config.hpp"
#include "flag_gpu.hpp"
#include "flag_tiles.hpp"
#include "gpu_test_support.hpp"
#include "naive_gather.hpp"
#include "naive_gpu.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "test_support.hpp"
#include "vk/compute_pipeline.hpp"
#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;

FilterOptions options_for(const std::string& method, const GatherPattern& pattern, bool adaptive, int tile_px = 16,
                          const std::string& precision = "", int scale = 1) {
  const Method& m = find_method(method);
  FilterOptions o = m.defaults(pattern);
  if (!precision.empty()) o.precision = precision;
  o.buffer_scale = scale;
  o.values["adaptive"] = adaptive ? 1 : 0;
  o.values["adaptive_tile_px"] = tile_px;
  // FLAG's worst case through the same 3D buffer as adaptive's (auto would run registers on lavapipe).
  if (const OptionSpec* buffer = m.option("layer_buffer")) o.values["layer_buffer"] = buffer->parse("full");
  return o;
}

double choice(const std::string& method, const std::string& key, const std::string& name) {
  return find_method(method).option(key)->parse(name);
}

// A scene of colour noise at the focal plane (radius 0) with `blurred` pixels at other depths.
struct Blurred {
  int x, y;
  float depth_m;
};
Scene focal_plane_scene(int w, int h, const std::vector<Blurred>& blurred, unsigned seed = 3) {
  Scene s{"test", random_image(w, h, 3, 0.0f, 1.0f, seed), Image(w, h, 1, 3.0f), Lens{}};
  for (const auto& b : blurred) {
    *s.depth_m.px(b.x, b.y) = b.depth_m;
    for (int c = 0; c < 3; ++c) s.color.px(b.x, b.y)[c] = 50.0f + 10.0f * c;
  }
  return s;
}

// Radii for the packed input: random, with a third of the pixels at 0.
Image random_packed(int w, int h, float max_radius, unsigned seed) {
  Image packed = random_image(w, h, 4, 0.0f, 1.0f, seed);
  const Image radius = random_image(w, h, 1, -0.5f * max_radius, max_radius, seed + 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) packed.px(x, y)[3] = std::max(0.0f, radius.px(x, y)[0]);
  return packed;
}

// ---- The tile map (CPU), against brute force ----

TEST(CocTiles, NoSourceThatReachesAPixelLiesOutsideItsTilesDisc) {
  for (const GatherPattern p : {GatherPattern{9, 2}, GatherPattern{7, 3}, GatherPattern{11, 1}})
    for (int tile_px : {5, 8, 16}) {
      const Image packed = random_packed(53, 41, p.max_radius_px() * 1.1f, 11);
      const CocTiles t = coc_tiles(packed, p, tile_px);
      const int n = p.half(), k = p.spacing_px, cap = 2 * n * n;
      int largest = 0;
      for (int y = 0; y < packed.height; ++y)
        for (int x = 0; x < packed.width; ++x) {
          const int tile = t.tile_of(x, y), m = disc_index(packed.px(x, y)[3] * packed.px(x, y)[3], k, cap);
          largest = std::max(largest, m);
          ASSERT_LE(m, t.max_index[tile]);
          ASSERT_LE(t.max_index[tile], t.reach_index[tile]);
          // Every source that adds to (x, y): its disc and the offset lie within the tile's D.
          for (int j = -n; j <= n; ++j)
            for (int i = -n; i <= n; ++i) {
              const int sx = x - i * k, sy = y - j * k;
              if (sx < 0 || sy < 0 || sx >= packed.width || sy >= packed.height) continue;
              const float r = packed.px(sx, sy)[3];
              if (!in_disc(r * r, i * k, j * k)) continue;
              ASSERT_LE(i * i + j * j, t.reach_index[tile]) << "pixel " << x << "," << y << " tile " << tile_px;
              ASSERT_LE(disc_index(r * r, k, cap), t.reach_index[tile]);
            }
        }
      EXPECT_EQ(t.scene_max_index, largest);
      // Each tile's M is the largest of its pixels (some pixel attains it).
      for (std::size_t tile = 0; tile < t.max_index.size(); ++tile) {
        bool attained = false;
        for (int y = 0; y < packed.height && !attained; ++y)
          for (int x = 0; x < packed.width && !attained; ++x)
            attained = t.tile_of(x, y) == static_cast<int>(tile) &&
                       disc_index(packed.px(x, y)[3] * packed.px(x, y)[3], k, cap) == t.max_index[tile];
        EXPECT_TRUE(attained) << "tile " << tile;
      }
    }
}

// Every layer FLAG's vertical pass reads in a tile that gathers (D > 0) lies in a tile whose Z covers it.
TEST(CocTiles, FlagWriteLayersCoverEveryVerticalRead) {
  for (const GatherPattern p : {GatherPattern{9, 2}, GatherPattern{7, 3}})
    for (int tile_px : {5, 8, 16}) {
      const Image packed = random_packed(47, 61, p.max_radius_px() * 0.6f, 21);
      const CocTiles t = coc_tiles(packed, p, tile_px);
      const int n = p.half(), k = p.spacing_px;
      const std::vector<int> z = flag_write_layers(t, k, n);
      for (int y = 0; y < packed.height; ++y)
        for (int x = 0; x < packed.width; ++x) {
          const int d = t.reach_index[t.tile_of(x, y)];
          if (d == 0) continue;
          const int rows = static_cast<int>(std::min<std::int64_t>(isqrt(d), n));
          for (int j = -rows; j <= rows; ++j) {
            const int sy = y + j * k;
            if (sy < 0 || sy >= packed.height) continue;
            ASSERT_GE(z[t.tile_of(x, sy)], std::abs(j)) << x << "," << y << " reads row " << sy;
          }
        }
    }
}

// FLAG with the layers the scene's largest disc reaches gives the image of all ceil(N/2) layers.
TEST(CocTiles, SceneSizedFlagEqualsTheFullPatternBitForBit) {
  const GatherPattern p{21, 2};
  for (float radius : {3.5f, 9.2f, 14.0f}) {
    const Image packed = random_packed(60, 44, radius, 31);
    const CocTiles t = coc_tiles(packed, p, 16);
    const GatherPattern sized = scene_sized_pattern(p, t.scene_max_index);
    EXPECT_LT(sized.layers(), p.layers()) << radius;
    for (LayerPrecision precision : {LayerPrecision::f32, LayerPrecision::f16, LayerPrecision::unorm16_bracketed})
      EXPECT_TRUE(same_bits(flag_blur(packed, sized, precision, 2), flag_blur(packed, p, precision, 2)))
          << radius << " " << to_string(precision);
  }
}

// ---- The tile map on the GPU: the same integers ----

TEST(CocTilesGpu, EqualsTheCpuMapIntegerForInteger) {
  for (const char* scene : {"hoops", "half_defocused", "mostly_in_focus"})
    for (const GatherPattern p : {GatherPattern{9, 2}, GatherPattern{7, 3}})
      for (int tile_px : {5, 16}) {
        const Scene s = make_scene(scene, 83, 61);
        const Lens lens = with_max_coc_radius(s.lens, s.depth_m, p.max_radius_px() * 1.1);
        gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, p);
        gpu::CocTilesGpu tiles(context(), frame.packed, frame.width(), frame.height(), p.spacing_px, tile_px);
        context().submit_and_wait([&](VkCommandBuffer cmd) {
          frame.coc_pass.dispatch(cmd, &frame.params, frame.width(), frame.height());
          tiles.record(cmd, nullptr, frame.params);
        });
        const CocTiles cpu = coc_tiles(frame.read_packed(), p, tile_px);
        const CocTiles gpu = tiles.read(83, 61);
        EXPECT_EQ(gpu.max_index, cpu.max_index) << scene << " tile " << tile_px;
        EXPECT_EQ(gpu.reach_index, cpu.reach_index) << scene << " tile " << tile_px;
        EXPECT_EQ(gpu.scene_max_index, cpu.scene_max_index);
        EXPECT_EQ(tiles.read_scene_max_index(), cpu.scene_max_index);
      }
}

TEST(CocTilesGpu, FlagWriteLayersEqualTheCpuOnes) {
  for (const GatherPattern p : {GatherPattern{9, 2}, GatherPattern{7, 3}})
    for (int tile_px : {5, 8}) {
      const Scene s = make_scene("half_defocused", 90, 70);
      const Lens lens = with_max_coc_radius(s.lens, s.depth_m, p.max_radius_px());
      gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, p);
      gpu::CocTilesGpu tiles(context(), frame.packed, frame.width(), frame.height(), p.spacing_px, tile_px);
      vk::ComputePipeline layers(context(), vk::spirv("flag/tile_layers"), {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                 sizeof(gpu::PassParams), {p.spacing_px, tile_px});
      layers.bind(0, tiles.buffer());
      const int n = p.half() - 1;  // as if the scene needed one layer less than the pattern has
      context().submit_and_wait([&](VkCommandBuffer cmd) {
        frame.coc_pass.dispatch(cmd, &frame.params, frame.width(), frame.height());
        tiles.record(cmd, nullptr, frame.params);
        gpu::PassParams params = frame.params;
        params.half_n = n;
        layers.dispatch(cmd, &params, (90 + tile_px - 1) / tile_px, (70 + tile_px - 1) / tile_px);
      });
      std::vector<int> gpu_z;
      tiles.read(90, 70, &gpu_z);
      const CocTiles cpu = coc_tiles(frame.read_packed(), p, tile_px);
      EXPECT_EQ(gpu_z, flag_write_layers(cpu, p.spacing_px, n)) << "N " << p.size_n << " tile " << tile_px;
    }
}

// The adaptive FLAG filter reports what the CPU map finds in the same frame.
TEST(CocTilesGpu, FlagStatsAgreeWithTheCpuMap) {
  const GatherPattern p{9, 2};
  const Scene s = make_scene("half_defocused", 90, 70);
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, 6.0);
  gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, p);
  auto filter = find_method("flag").make_gpu(frame, options_for("flag", p, true, 8, "f32"));
  vk::TimestampQueries timer(context(), 16);
  gpu::run_frames(frame, *filter, timer);
  const CocTiles cpu = coc_tiles(frame.read_packed(), p, 8);
  const auto stats = filter->stats()["adaptive"];
  EXPECT_EQ(stats["layers"].get<int>(), scene_sized_pattern(p, cpu.scene_max_index).layers());
  nlohmann::json expected = coc_tiles_stats(cpu, p, 90, 70);
  expected.update({{"layers", stats["layers"]}, {"layers_worst_case", p.layers()},
                   {"scene_max_disc_index_when_prepared", cpu.scene_max_index}});
  EXPECT_EQ(stats, expected);
}

// ---- Adaptive against worst case ----

struct Case {
  std::string name;
  Scene scene;
  Lens lens;
  GatherPattern pattern;
};

// Mixed CoC: procedural scenes, a large disc whose source lies one pixel outside a tile (left of it,
// above it, diagonally), and a single blurred pixel.
std::vector<Case> cases() {
  std::vector<Case> out;
  for (const char* name : {"hoops", "half_defocused", "mostly_in_focus"}) {
    const Scene s = make_scene(name, 77, 58);
    for (const GatherPattern p : {GatherPattern{9, 2}, GatherPattern{7, 3}, GatherPattern{11, 1}})
      out.push_back({std::string(name) + "_N" + std::to_string(p.size_n) + "k" + std::to_string(p.spacing_px), s,
                     with_max_coc_radius(s.lens, s.depth_m, p.max_radius_px() * 1.2), p});
  }
  {
    // Tiles of 16 px: sources at x = 31 (tile 1's last column), y = 15 (tile row 0's last row) and
    // (47, 47) (a tile corner), each of radius 8 px reaching 8 px into the next tiles.
    const Scene s = focal_plane_scene(80, 64, {{31, 20, 30.0f}, {40, 15, 30.0f}, {47, 47, 30.0f}});
    out.push_back({"edge_sources", s, with_max_coc_radius(s.lens, s.depth_m, 8.2), GatherPattern{9, 2}});
    out.push_back({"edge_sources_k1", s, with_max_coc_radius(s.lens, s.depth_m, 8.2), GatherPattern{17, 1}});
  }
  {
    const Scene s = focal_plane_scene(70, 50, {{33, 22, 20.0f}});
    out.push_back({"single_blurred_pixel", s, with_max_coc_radius(s.lens, s.depth_m, 6.5), GatherPattern{9, 2}});
  }
  return out;
}

TEST(AdaptiveGather, NaiveEqualsTheWorstCaseBitForBitOnGpuAndCpu) {
  for (const Case& c : cases()) {
    const Method& naive = find_method("naive");
    const Image worst = run_gpu(context(), naive, c.scene.color, c.scene.depth_m, c.lens, options_for("naive", c.pattern, false));
    const Image worst_cpu = run_cpu(naive, c.scene.color, c.scene.depth_m, c.lens, options_for("naive", c.pattern, false), 2);
    for (const char* block : {"1x1", "8x4"})
      for (int tile_px : {5, 8, 16}) {
        FilterOptions o = options_for("naive", c.pattern, true, tile_px);
        o.values["gather_block"] = choice("naive", "gather_block", block);
        EXPECT_TRUE(same_bits(run_gpu(context(), naive, c.scene.color, c.scene.depth_m, c.lens, o), worst))
            << c.name << " block " << block << " tile " << tile_px;
      }
    for (int tile_px : {5, 16})
      EXPECT_TRUE(same_bits(run_cpu(naive, c.scene.color, c.scene.depth_m, c.lens, options_for("naive", c.pattern, true, tile_px), 2),
                            worst_cpu))
          << c.name << " CPU tile " << tile_px;
  }
}

// FLAG: where something blurred reaches the tile, the same bits; where nothing does, the input
// itself against the worst case's round trip through one stored layer: within the format's rounding
// of that value (storage_tolerance: 0 for f32, one ulp for f16 / r11g11b10f relative to the value)
// or, bracketed, one code of its row's layer-0 range (relative to the largest value). Scan bins: the
// f32 summation tolerance everywhere (shaders/flag/horizontal_scan.comp says why not the same bits).
void expect_flag_within_bound(const Image& adaptive, const Image& worst, const Image& packed, const GatherPattern& p,
                              int tile_px, const FilterOptions& o, const std::string& what) {
  const LayerPrecision precision = layer_precision_from_string(o.precision);
  const bool scan = flag_config(o).horizontal_bins == FlagHorizontalBins::scan;
  double largest = 0;
  for (float v : worst.pixels) largest = std::max(largest, double(std::abs(v)));
  const CocTiles t = coc_tiles(packed, p, tile_px);
  for (int y = 0; y < worst.height; ++y)
    for (int x = 0; x < worst.width; ++x) {
      const bool through = t.reach_index[t.tile_of(x, y)] == 0;
      for (int c = 0; c < 3; ++c) {
        const float a = adaptive.px(x, y)[c], w = worst.px(x, y)[c];
        if (scan) {  // the worst case also adds the residues of layers nothing reaches
          if (through) ASSERT_EQ(a, packed.px(x, y)[c]) << what << ": a tile passed through outputs its input";
          ASSERT_LE(std::abs(double(a) - w), find_method("flag").gpu_tolerance(o) * largest)
              << what << " at " << x << "," << y;
          continue;
        }
        if (!through || precision == LayerPrecision::f32) {
          ASSERT_EQ(std::memcmp(&a, &w, sizeof(float)), 0) << what << " at " << x << "," << y << ": " << a << " vs " << w;
          continue;
        }
        ASSERT_EQ(a, packed.px(x, y)[c]) << what << ": a tile passed through outputs its input";
        // One stored value: one ulp of it (a driver may round either way; plus the format's
        // subnormal spacing), or bracketed one code of its row's layer-0 range, which no output
        // exceeds (layer 0 of a pixel's own row is part of its sum of non-negative layers).
        const double bound = is_bracketed(precision)
                                 ? largest / bracket_levels(precision)
                                 : find_method("flag").storage_tolerance(o) * std::abs(w) + std::ldexp(1.0, -18);
        ASSERT_LE(std::abs(double(a) - w), bound * (1 + 1e-6)) << what << " at " << x << "," << y;
      }
    }
}

TEST(AdaptiveGather, FlagEqualsTheWorstCaseWithinOneRoundingOfItsFormat) {
  const Method& flag = find_method("flag");
  for (const Case& c : cases())
    for (const std::string& precision : flag.precisions)
      for (const double bins : {0.0, 3.0}) {  // auto, and scan
        FilterOptions off = options_for("flag", c.pattern, false, 16, precision);
        off.values["horizontal_bins"] = bins;
        gpu::GpuFrame frame(context(), c.scene.color, c.scene.depth_m, c.lens, c.pattern);
        vk::TimestampQueries timer(context(), 32);
        auto worst_filter = flag.make_gpu(frame, off);
        gpu::run_frames(frame, *worst_filter, timer);
        const Image worst = frame.read_output(), packed = frame.read_packed();
        for (int tile_px : {5, 16}) {
          FilterOptions on = options_for("flag", c.pattern, true, tile_px, precision);
          on.values["horizontal_bins"] = bins;
          auto filter = flag.make_gpu(frame, on);
          gpu::warm_up(frame, *filter, timer);  // a smaller region first: the next frame must not depend on it
          gpu::run_frames(frame, *filter, timer);
          expect_flag_within_bound(frame.read_output(), worst, packed, c.pattern, tile_px, on,
                                   c.name + " " + precision + " bins " + flag_horizontal_bins()[std::size_t(bins)] +
                                       " tile " + std::to_string(tile_px));
        }
      }
}

// Reduced buffers: adaptive runs on the low-res grid; against the worst case within the bound of one
// stored value through the upsample (its bilinear weights sum to one).
TEST(AdaptiveGather, FlagReducedBuffersStayWithinTheBound) {
  const Method& flag = find_method("flag");
  const Scene s = make_scene("half_defocused", 96, 72);
  const GatherPattern p{13, 2};
  const Lens lens = with_max_coc_radius(s.lens, s.depth_m, p.max_radius_px());
  for (int scale : {2, 4})
    for (const std::string& precision : {std::string("f32"), std::string("f16"), std::string("unorm10_bracketed")}) {
      const FilterOptions off = options_for("flag", p, false, 16, precision, scale);
      const FilterOptions on = options_for("flag", p, true, 16, precision, scale);
      const Image worst = run_gpu(context(), flag, s.color, s.depth_m, lens, off);
      const Image adaptive = run_gpu(context(), flag, s.color, s.depth_m, lens, on);
      double largest = 0;
      for (float v : worst.pixels) largest = std::max(largest, double(std::abs(v)));
      const double bound = flag.storage_tolerance(on) * largest;
      EXPECT_LE(max_abs_diff(adaptive, worst), bound * (1 + 1e-6)) << precision << " 1/" << scale;
      if (precision == "f32") {
        EXPECT_TRUE(same_bits(adaptive, worst)) << "1/" << scale;
      }
      // The CPU reference of adaptive = on models the same pass-through.
      const Image cpu = run_cpu(flag, s.color, s.depth_m, lens, on, 2);
      EXPECT_LE(max_abs_diff(adaptive, cpu), flag.gpu_tolerance(on) * largest) << precision << " 1/" << scale;
    }
}

// ---- What is allocated follows the scene ----

TEST(AdaptiveGather, FlagLayersAndBytesFollowTheScenesLargestRadius) {
  const GatherPattern p{41, 2};
  const int w = 96, h = 64;
  const auto worst_layers = static_cast<std::uint32_t>(p.layers());
  const VkFormat format = layer_format(LayerPrecision::f16);
  const std::uint64_t worst_bytes = vk::image_3d_requirement_bytes(context(), format, w, h, worst_layers);
  std::uint64_t previous = 0;
  // Radii away from disc-index boundaries: floor(r^2 / 4) = 4, 37, 103, 229, 400 (clamped).
  for (double radius : {4.3, 12.3, 20.3, 30.3, 45.0}) {
    const Scene s = focal_plane_scene(w, h, {{40, 30, 30.0f}});
    const Lens lens = with_max_coc_radius(s.lens, s.depth_m, radius);
    const double r = std::min(radius, 40.0);
    const int index = static_cast<int>(r * r / 4);
    const auto layers = static_cast<std::uint32_t>(std::min<std::int64_t>(isqrt(index), 20) + 1);
    gpu::GpuFrame frame(context(), s.color, s.depth_m, lens, p);
    auto filter = find_method("flag").make_gpu(frame, options_for("flag", p, true));
    vk::TimestampQueries timer(context(), 16);
    gpu::run_frames(frame, *filter, timer);
    EXPECT_EQ(filter->stats()["adaptive"]["layers"].get<std::uint32_t>(), layers) << radius;
    const std::uint64_t image = vk::image_3d_requirement_bytes(context(), format, w, h, layers);
    const std::uint64_t tile_map = gpu::CocTilesGpu::bytes(w, h, 16);
    EXPECT_GE(filter->intermediate_bytes(), image + tile_map) << radius;
    EXPECT_LE(filter->intermediate_bytes(), image + 4 * tile_map + 4096) << radius;  // allocation granularity
    EXPECT_GT(filter->intermediate_bytes(), previous);
    previous = filter->intermediate_bytes();
    if (layers < worst_layers) {
      EXPECT_LT(filter->intermediate_bytes(), worst_bytes);
    }
    // The worst case allocates ceil(N/2) layers whatever the scene.
    auto worst = find_method("flag").make_gpu(frame, options_for("flag", p, false));
    EXPECT_GE(worst->intermediate_bytes(), worst_bytes);
  }
}

TEST(AdaptiveGather, AnAllInFocusSceneCostsAlmostNothingAndReturnsTheInput) {
  const Scene s = focal_plane_scene(100, 70, {});  // every depth on the focal plane: radius 0
  const GatherPattern p{41, 2};
  for (const char* method : {"naive", "flag"})
    for (const std::string& precision : find_method(method).precisions) {
      const FilterOptions o = options_for(method, p, true, 16, precision);
      gpu::GpuFrame frame(context(), s.color, s.depth_m, s.lens, p);
      auto filter = find_method(method).make_gpu(frame, o);
      vk::TimestampQueries timer(context(), 16);
      gpu::run_frames(frame, *filter, timer);
      EXPECT_TRUE(same_bits(frame.read_output(), s.color)) << method << " " << precision;
      const auto stats = filter->stats()["adaptive"];
      EXPECT_EQ(stats["tiles_passed_through"], stats["tiles"]);
      EXPECT_DOUBLE_EQ(stats["gather_sample_fraction"].get<double>(), 1.0 / p.samples_per_pixel());
      // Only the tile map (and for FLAG one placeholder texel and, bracketed, a row's brackets).
      EXPECT_LE(filter->intermediate_bytes(), 64u * 1024) << method << " " << precision;
      EXPECT_TRUE(same_bits(run_cpu(find_method(method), s.color, s.depth_m, s.lens, o, 2), s.color)) << method;
    }
}

}  // namespace
}  // namespace bokeh
