// sprites: detection counts, overflow, the sprite texture, identity, energy and CPU/GPU agreement,
// each against a closed form or a conservation law (kernels/sprites/sprites.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "coc.hpp"
#include "exact_scatter.hpp"
#include "method.hpp"
#include "metrics.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "sprites.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;

const Method& sprites() { return find_method("sprites"); }

vk::Context& context() {
  static vk::Context ctx("", sprites().needs(sprites().defaults({9, 2})));
  return ctx;
}

#define SKIP_IF_NO_GRAPHICS()                                                                            \
  do {                                                                                                   \
    if (const std::string missing = context().unmet(sprites().needs(sprites().defaults({9, 2})));      \
        !missing.empty())                                                                                \
      GTEST_SKIP() << "sprites needs " << missing << ", which " << context().info().name << " lacks";  \
  } while (false)

struct Highlight {
  int x, y;
  float radiance;
  bool in_focus = false;  // at the focus distance: radius 0, below any min radius
};

// A backdrop (constant, or a gentle gradient whose neighbours differ by far less than the threshold)
// at 10 m, with the highlights; the lens puts every defocused pixel at `radius_px`.
struct TestScene {
  Image color, depth_m;
  Lens lens;
};
TestScene highlight_scene(int w, int h, const std::vector<Highlight>& lights, float radius_px, bool gradient) {
  TestScene s{Image(w, h, 3), Image(w, h, 1, 10.0f), Lens{}};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) s.color.px(x, y)[c] = gradient ? 0.1f + 0.2f * x / w + 0.05f * c : 0.0f;
  for (const Highlight& l : lights) {
    for (int c = 0; c < 3; ++c) s.color.px(l.x, l.y)[c] += l.radiance;
    if (l.in_focus) *s.depth_m.px(l.x, l.y) = static_cast<float>(s.lens.focus_distance_m);
  }
  s.lens = with_max_coc_radius(s.lens, s.depth_m, radius_px);
  return s;
}

// Twelve isolated highlights on a 4 x 3 grid, 24 px apart.
std::vector<Highlight> grid_of_highlights(float radiance) {
  std::vector<Highlight> lights;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 4; ++i) lights.push_back({12 + 24 * i, 12 + 20 * j, radiance});
  return lights;
}

FilterOptions options(const GatherPattern& pattern, double max_sprites = 65536, double threshold = 1.0,
                      double min_radius = 3.0) {
  FilterOptions o = sprites().defaults(pattern);
  o.values["max_sprites"] = max_sprites;
  o.values["sprite_threshold"] = threshold;
  o.values["sprite_min_radius"] = min_radius;
  return o;
}


double max_abs(const Image& img) {
  double m = 0;
  for (float v : img.pixels) m = std::max(m, double(std::abs(v)));
  return m;
}

// Runs on both backends; returns {CPU, GPU} outputs and their stats.
struct Both {
  Image cpu, gpu;
  nlohmann::json cpu_stats, gpu_stats;
};
Both run_both(const TestScene& s, const FilterOptions& o) {
  Both b;
  b.cpu = run_cpu(sprites(), s.color, s.depth_m, s.lens, o, 2, &b.cpu_stats);
  b.gpu = run_gpu(context(), sprites(), s.color, s.depth_m, s.lens, o, nullptr, &b.gpu_stats);
  return b;
}

TEST(Sprites, DetectsEachIsolatedHighlightAndNothingElse) {
  SKIP_IF_NO_GRAPHICS();
  // 12 highlights 5 above a gradient backdrop (detected); 3 only 0.9 above it (under the threshold of
  // 1); 2 bright but in focus (radius 0 < the 3 px minimum). Radius 6.5 px elsewhere.
  std::vector<Highlight> lights = grid_of_highlights(5.0f);
  for (int i = 0; i < 3; ++i) lights.push_back({24 + 24 * i, 22, 0.9f});
  lights.push_back({24, 42, 20.0f, true});
  lights.push_back({48, 42, 20.0f, true});
  const TestScene s = highlight_scene(96, 64, lights, 6.5f, true);
  const FilterOptions o = options({17, 1});

  const CocInput coc = cpu_coc_pass(s.color, s.depth_m, s.lens, o.pattern);
  const SpriteDetection d = detect_sprites(s.color, coc.packed, {1.0f, 3.0f, 65536});
  ASSERT_EQ(d.sprites.size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) {  // row-major order: the grid's order
    EXPECT_EQ(d.sprites[i].x_px, 12 + 24 * int(i % 4));
    EXPECT_EQ(d.sprites[i].y_px, 12 + 20 * int(i / 4));
  }

  const Both b = run_both(s, o);
  const int side = 2 * 6 + 1;
  for (const auto* stats : {&b.cpu_stats, &b.gpu_stats}) {
    SCOPED_TRACE(stats == &b.cpu_stats ? "CPU" : "GPU");
    EXPECT_EQ((*stats)["sprites_detected"], 12);
    EXPECT_EQ((*stats)["sprites_drawn"], 12);
    EXPECT_EQ((*stats)["sprites_overflowed"], 0);
    EXPECT_EQ((*stats)["sprite_overflow"], false);
    EXPECT_EQ((*stats)["sprite_quad_pixels"], 12 * side * side);
  }
}

TEST(Sprites, OverflowPastTheMaximumIsCountedReportedAndKeepsTheLight) {
  SKIP_IF_NO_GRAPHICS();
  const TestScene s = highlight_scene(96, 64, grid_of_highlights(5.0f), 6.5f, false);
  const FilterOptions o = options({17, 1}, 5);
  const Both b = run_both(s, o);
  const double in = rgb_sum(s.color);
  for (const auto& [stats, out, side] : {std::tuple{&b.cpu_stats, &b.cpu, "CPU"}, {&b.gpu_stats, &b.gpu, "GPU"}}) {
    SCOPED_TRACE(side);
    EXPECT_EQ((*stats)["sprites_detected"], 12);
    EXPECT_EQ((*stats)["sprites_drawn"], 5);
    EXPECT_EQ((*stats)["sprites_overflowed"], 7);
    EXPECT_EQ((*stats)["sprite_overflow"], true);
    EXPECT_EQ((*stats)["max_sprites"], 5);
    // The 7 left over are gathered instead: nothing is lost (every disc lies inside the image).
    EXPECT_NEAR(rgb_sum(*out) / in, 1.0, 1e-5);
  }
  // max_sprites 0: every highlight overflows into the gather, which is then the naive gather.
  const Both none = run_both(s, options({17, 1}, 0));
  EXPECT_EQ(none.gpu_stats["sprites_overflowed"], 12);
  EXPECT_EQ(none.gpu_stats["sprites_drawn"], 0);
  const Image naive = run_cpu(find_method("naive"), s.color, s.depth_m, s.lens, find_method("naive").defaults({17, 1}), 2);
  EXPECT_LE(max_abs_diff(none.gpu, naive), 1e-5 * max_abs(naive));
  EXPECT_EQ(max_abs_diff(none.cpu, naive), 0.0);
}

// A point light at a constant CoC: the sprite texture is the disc of that radius, every pixel whose
// centre lies within r of the light's centre lit with radiance / (their count), the rest black.
TEST(Sprites, PointLightGivesTheDiscOfItsRadius) {
  SKIP_IF_NO_GRAPHICS();
  const int cx = 31, cy = 30;
  const float radiance = 100.0f;
  for (const float radius : {3.5f, 6.5f, 10.5f}) {
    SCOPED_TRACE(radius);
    const TestScene s = highlight_scene(64, 64, {{cx, cy, radiance}}, radius, false);
    // k = 2: the gather alone would light only every other pixel of the disc.
    const Both b = run_both(s, options({25, 2}));
    long count = 0;  // the closed form, in integers
    const double r2 = double(radius) * radius;
    for (int dy = -20; dy <= 20; ++dy)
      for (int dx = -20; dx <= 20; ++dx) count += dx * dx + dy * dy <= r2;
    EXPECT_EQ(disc_pixel_count(radius), count);
    for (const auto& [out, side] : {std::pair{&b.cpu, "CPU"}, {&b.gpu, "GPU"}}) {
      SCOPED_TRACE(side);
      long lit = 0;
      int extent = 0;
      for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
          const int dx = x - cx, dy = y - cy;
          const double expected = dx * dx + dy * dy <= r2 ? radiance / count : 0.0;
          for (int c = 0; c < 3; ++c) ASSERT_NEAR(out->px(x, y)[c], expected, 1e-6 * radiance) << x << "," << y;
          if (out->px(x, y)[0] > 0) ++lit, extent = std::max(extent, std::abs(dx));
        }
      EXPECT_EQ(lit, count);
      EXPECT_EQ(extent, static_cast<int>(radius));
    }
  }
}

// Radius 0 with sprites drawn (minimum radius 0): each sprite lands on its own pixel alone.
TEST(Sprites, RadiusZeroIsTheIdentityEvenWithSpritesDrawn) {
  SKIP_IF_NO_GRAPHICS();
  TestScene s = highlight_scene(96, 64, grid_of_highlights(5.0f), 6.5f, true);
  s.lens.f_stop = 1e12;  // a pinhole
  const Both b = run_both(s, options({9, 2}, 65536, 1.0, 0.0));
  EXPECT_EQ(b.cpu_stats["sprites_drawn"], 12);
  EXPECT_EQ(b.gpu_stats["sprites_drawn"], 12);
  EXPECT_LE(max_abs_diff(b.cpu, s.color), 1e-6 * max_abs(s.color));
  EXPECT_LE(max_abs_diff(b.gpu, s.color), 1e-6 * max_abs(s.color));
}

// Energy: with every disc inside the image, the output's total equals the input's, whatever share
// the sprites take (the method says: sprite weights and gather weights both sum to the colour).
TEST(Sprites, EnergyIsConservedWhateverTheSpritesTake) {
  SKIP_IF_NO_GRAPHICS();
  const int w = 80, h = 64, margin = 10;
  const Image color = random_image_in_black_border(w, h, margin, 11);
  const Image depth(w, h, 1, 10.0f);
  const TestScene s{color, depth, with_max_coc_radius(Lens{}, depth, 8.0)};
  const double in = rgb_sum(color);
  for (const double threshold : {0.25, 1.0, 100.0}) {
    SCOPED_TRACE(threshold);
    const Both b = run_both(s, options({17, 1}, 65536, threshold));
    if (threshold < 100) {
      EXPECT_GT(b.gpu_stats["sprites_drawn"].get<int>(), 100);
    }
    EXPECT_EQ(b.gpu_stats["sprites_detected"], b.cpu_stats["sprites_detected"]);
    EXPECT_NEAR(rgb_sum(b.cpu) / in, 1.0, 1e-5);
    EXPECT_NEAR(rgb_sum(b.gpu) / in, 1.0, 1e-5);
  }
}

TEST(Sprites, GpuMatchesCpuWithTheSameSpritesAndPasses) {
  SKIP_IF_NO_GRAPHICS();
  const Scene scene = make_scene("hoops", 160, 120);
  const FilterOptions o = options({13, 2});
  const TestScene s{scene.color, scene.depth_m, with_max_coc_radius(scene.lens, scene.depth_m, 12 * 1.2)};
  Both b;
  std::vector<vk::PassTime> passes;
  b.cpu = run_cpu(sprites(), s.color, s.depth_m, s.lens, o, 2, &b.cpu_stats);
  b.gpu = run_gpu(context(), sprites(), s.color, s.depth_m, s.lens, o, &passes, &b.gpu_stats);
  EXPECT_GT(b.cpu_stats["sprites_drawn"].get<int>(), 10);
  EXPECT_EQ(b.gpu_stats, b.cpu_stats);
  const double error = max_abs_diff(b.gpu, b.cpu) / max_abs(b.cpu);
  std::printf("[sprites] hoops 160x120 N=13: %d sprites, GPU vs CPU %.3g of the largest value (bound %.3g)\n",
              b.cpu_stats["sprites_drawn"].get<int>(), error, sprites().gpu_tolerance(o));
  EXPECT_LE(error, sprites().gpu_tolerance(o));
  std::vector<std::string> names;
  for (const auto& p : passes) names.push_back(p.pass);
  EXPECT_EQ(names, (std::vector<std::string>{"coc", "detect", "gather", "sprites"}));
}

// What the sprites are for: a sparse gather (k = 2) dots each highlight's disc; the sprites draw it
// whole, so the result is closer to the exact scatter than naive at the same pattern. What remains
// is the disc edge (pixel centres against exact area coverage) and the lights under the minimum
// radius, which stay dotted: measured RMSE 0.377 against naive's 0.605.
TEST(Sprites, CloserToTheExactScatterThanNaiveOnPointLights) {
  SKIP_IF_NO_GRAPHICS();
  const Scene scene = make_scene("points", 128, 96);
  const GatherPattern pattern{17, 2};
  const Lens lens = with_max_coc_radius(scene.lens, scene.depth_m, pattern.max_radius_px());
  const Image radius = coc_radius_image(scene.depth_m, lens, pattern.max_radius_px());
  const Image exact = exact_scatter(scene.color, radius, scene.depth_m, ScatterComposite::energy_sum, 2);
  const Image naive = run_cpu(find_method("naive"), scene.color, scene.depth_m, lens, find_method("naive").defaults(pattern), 2);
  nlohmann::json stats;
  const Image splat = run_gpu(context(), sprites(), scene.color, scene.depth_m, lens, options(pattern), nullptr, &stats);
  const double naive_rmse = compare_images(naive, exact).rmse, sprites_rmse = compare_images(splat, exact).rmse;
  std::printf("[sprites] points 128x96 N=17 k=2: RMSE vs exact scatter naive %.4g, sprites %.4g (%d sprites)\n",
              naive_rmse, sprites_rmse, stats["sprites_drawn"].get<int>());
  EXPECT_LT(sprites_rmse, 0.75 * naive_rmse);
}

// Apertures (issue 23). The shapes every test below draws: a pentagon pointing up (not symmetric
// about the horizontal), a hexagon on and off its 60-degree grid, rotated curved blades, nine blades.
std::vector<Aperture> shapes() {
  return {parse_aperture("blades5"), parse_aperture("blades6"), parse_aperture("blades6-rot15"),
          parse_aperture("blades7-rot20-curv0.5"), parse_aperture("blades9")};
}

FilterOptions shape_options(const GatherPattern& pattern, const Aperture& aperture, double threshold = 1.0) {
  FilterOptions o = options(pattern, 65536, threshold);
  o.aperture = aperture;
  return o;
}

TestScene with_shape(TestScene s, const Aperture& aperture) {
  s.lens.aperture = aperture;
  return s;
}

// A point light at a constant CoC: the sprite is the aperture of circumradius r, every pixel whose
// integer offset from the light lies in the shape (Aperture::gauge in double, the closed form) lit
// with radiance / (their count), the rest black, on both backends.
TEST(SpritesAperture, PointLightGivesItsShape) {
  SKIP_IF_NO_GRAPHICS();
  const int cx = 31, cy = 30;
  const float radiance = 100.0f;
  for (const Aperture& a : shapes())
    for (const float radius : {6.5f, 10.5f}) {
      SCOPED_TRACE(a.name() + " r " + std::to_string(radius));
      const TestScene s = with_shape(highlight_scene(64, 64, {{cx, cy, radiance}}, radius, false), a);
      const Both b = run_both(s, shape_options({25, 2}, a));
      long count = 0;
      for (int dy = -12; dy <= 12; ++dy)
        for (int dx = -12; dx <= 12; ++dx) {
          const double g = a.gauge(dx, dy);
          ASSERT_GT(std::abs(g - radius), 1e-4) << dx << "," << dy;  // no offset on the edge: float tests agree
          count += g <= radius;
        }
      EXPECT_LT(count, disc_pixel_count(radius));  // a polygon inside its circumscribed disc
      for (const auto& [out, stats, side] : {std::tuple{&b.cpu, &b.cpu_stats, "CPU"}, {&b.gpu, &b.gpu_stats, "GPU"}}) {
        SCOPED_TRACE(side);
        EXPECT_EQ((*stats)["sprites_drawn"], 1);
        long lit = 0;
        for (int y = 0; y < 64; ++y)
          for (int x = 0; x < 64; ++x) {
            const double expected = a.gauge(x - cx, y - cy) <= radius ? radiance / count : 0.0;
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(out->px(x, y)[c], expected, 1e-6 * radiance) << x << "," << y;
            lit += out->px(x, y)[0] > 0;
          }
        EXPECT_EQ(lit, count);
      }
    }
  // The pentagon points up: its vertex reaches 10 px above the light, its flat edge (10.5 cos 36 deg =
  // 8.5 px) not 9 px below.
  const TestScene s = with_shape(highlight_scene(64, 64, {{cx, cy, radiance}}, 10.5f, false), parse_aperture("blades5"));
  const Both b = run_both(s, shape_options({25, 2}, parse_aperture("blades5")));
  EXPECT_GT(b.gpu.px(cx, cy - 10)[0], 0.0f);
  EXPECT_EQ(b.gpu.px(cx, cy + 9)[0], 0.0f);
}

// Energy: with every shape inside the image, the output's total equals the input's, whatever share
// the sprites take (their weights and naive's shape weights each sum to the source's colour).
TEST(SpritesAperture, EnergyIsConservedForEveryShape) {
  SKIP_IF_NO_GRAPHICS();
  const int w = 80, h = 64, margin = 10;
  const Image color = random_image_in_black_border(w, h, margin, 11);
  const Image depth(w, h, 1, 10.0f);
  const double in = rgb_sum(color);
  for (const Aperture& a : shapes())
    for (const double threshold : {0.25, 100.0}) {
      SCOPED_TRACE(a.name() + " threshold " + std::to_string(threshold));
      TestScene s{color, depth, with_max_coc_radius(Lens{}, depth, 8.0)};
      s.lens.aperture = a;
      const Both b = run_both(s, shape_options({17, 1}, a, threshold));
      if (threshold < 100) EXPECT_GT(b.gpu_stats["sprites_drawn"].get<int>(), 100);
      EXPECT_EQ(b.gpu_stats["sprites_detected"], b.cpu_stats["sprites_detected"]);
      EXPECT_NEAR(rgb_sum(b.cpu) / in, 1.0, 1e-5);
      EXPECT_NEAR(rgb_sum(b.gpu) / in, 1.0, 1e-5);
    }
}

TEST(SpritesAperture, GpuMatchesCpuForEveryShapeWithTheSameSpritesAndPasses) {
  SKIP_IF_NO_GRAPHICS();
  const Scene scene = make_scene("hoops", 160, 120);
  for (const Aperture& a : shapes()) {
    SCOPED_TRACE(a.name());
    const FilterOptions o = shape_options({13, 2}, a);
    Lens lens = with_max_coc_radius(scene.lens, scene.depth_m, 12 * 1.2);
    lens.aperture = a;
    nlohmann::json cpu_stats, gpu_stats;
    std::vector<vk::PassTime> passes;
    const Image cpu = run_cpu(sprites(), scene.color, scene.depth_m, lens, o, 2, &cpu_stats);
    const Image gpu = run_gpu(context(), sprites(), scene.color, scene.depth_m, lens, o, &passes, &gpu_stats);
    EXPECT_GT(cpu_stats["sprites_drawn"].get<int>(), 10);
    EXPECT_EQ(gpu_stats, cpu_stats);
    const double error = max_abs_diff(gpu, cpu) / max_abs(cpu);
    std::printf("[sprites] %s hoops 160x120 N=13: %d sprites, GPU vs CPU %.3g of the largest value (bound %.3g)\n",
                a.name().c_str(), cpu_stats["sprites_drawn"].get<int>(), error, sprites().gpu_tolerance(o));
    EXPECT_LE(error, sprites().gpu_tolerance(o));
    std::vector<std::string> names;
    for (const auto& p : passes) names.push_back(p.pass);
    EXPECT_EQ(names, (std::vector<std::string>{"coc", "shape_pack", "detect", "gather", "sprites"}));
  }
}

// Against the exact scatter of the same shape (area coverage at the edge): the sprites draw each
// highlight's shape whole where naive's k = 2 gather dots it, as for the disc, and both sample the
// shape at pixel centres. Straight edges alias more than the disc's curve under that sampling, for
// naive as for the sprites: measured PSNR (dB) on points 128 x 96, N = 17, k = 2, sprites (naive):
// disc 48.47 (44.36); blades5 44.33 (41.84); blades6 46.04 (42.92), the same at rot30; blades6 at
// rot 5, 10, 15 or 45 41.39 (39.98); blades7-rot20-curv0.5 46.15 (43.12); blades9 44.34 (42.02).
TEST(SpritesAperture, PsnrAgainstTheExactScatterOfTheSameShapeIsNearTheDiscs) {
  SKIP_IF_NO_GRAPHICS();
  const Scene scene = make_scene("points", 128, 96);
  const GatherPattern pattern{17, 2};
  const Lens disc_lens = with_max_coc_radius(scene.lens, scene.depth_m, pattern.max_radius_px());
  const Image radius = coc_radius_image(scene.depth_m, disc_lens, pattern.max_radius_px());
  const auto psnr_of = [&](const Aperture& a, const std::string& method) {
    Lens lens = disc_lens;
    lens.aperture = a;
    const Image exact = exact_scatter(scene.color, radius, scene.depth_m, ScatterComposite::energy_sum, 2, a);
    FilterOptions o = method == "sprites" ? options(pattern) : find_method(method).defaults(pattern);
    o.aperture = a;
    const Image out = run_gpu(context(), find_method(method), scene.color, scene.depth_m, lens, o);
    return compare_images(out, exact).psnr_db;
  };
  const double disc = psnr_of(Aperture{}, "sprites");
  std::printf("[sprites] points 128x96 N=17 k=2, PSNR vs the exact scatter of the same shape, sprites (naive): disc "
              "%.2f dB (%.2f)", disc, psnr_of(Aperture{}, "naive"));
  for (const Aperture& a : shapes()) {
    const double shape = psnr_of(a, "sprites"), naive = psnr_of(a, "naive");
    std::printf(", %s %.2f (%.2f)", a.name().c_str(), shape, naive);
    EXPECT_GT(shape, disc - 7.5) << a.name();    // at worst (a hexagon off its axes) 7.1 dB under the disc
    EXPECT_GT(shape, naive + 1.0) << a.name();  // the sprites' point: whole shapes, not dotted ones
  }
  std::printf("\n");
}

// The shape's table covers every offset up to the pattern's largest radius, which is bounded: past
// it the method says so (and the disc, which needs no table, is not limited).
TEST(SpritesAperture, APatternBeyondTheShapeTableIsDeclaredUnsupported) {
  FilterOptions o = options({201, 3});  // 300 px
  o.aperture = parse_aperture("blades6");
  const std::string why = aperture_unsupported(sprites(), o);
  EXPECT_NE(why.find("256 px"), std::string::npos) << why;
  EXPECT_THROW(check_options(sprites(), o), std::invalid_argument);
  o.aperture = Aperture{};
  EXPECT_EQ(aperture_unsupported(sprites(), o), "");
  o = options({171, 3});  // 255 px
  o.aperture = parse_aperture("blades6");
  EXPECT_EQ(aperture_unsupported(sprites(), o), "");
}

// lavapipe stamps time late once a draw has bound a framebuffer unless the timing path forces a
// flush (kernels/vk/timestamps.cpp): each pass then reads as the next one, so after a sprites frame a
// naive frame's CoC pass took the gather's time and the gather next to none. The gather does N^2 =
// 1681 taps a pixel where the CoC pass does 41 columns: shifted stamps invert that order. Three
// draw-then-naive frames, their fastest compared: a pass can stall behind a process on the other core
// (clean-clone runs saw the CoC pass at 9.7 ms beside a 9.3 ms gather, and a median CoC of 8.95 ms
// beside 8.33), and a stall only adds time, where shifted stamps leave the gather next to nothing in
// every frame.
TEST(Sprites, TimestampsStayWithTheirPassesAfterADraw) {
  SKIP_IF_NO_GRAPHICS();
  const Scene scene = make_scene("hoops", 200, 150);
  const GatherPattern pattern{41, 2};
  const Lens lens = with_max_coc_radius(scene.lens, scene.depth_m, pattern.max_radius_px());
  std::vector<double> coc_ms, gather_ms;
  for (int frame = 0; frame < 3; ++frame) {
    run_gpu(context(), sprites(), scene.color, scene.depth_m, lens, options(pattern));
    std::vector<vk::PassTime> passes;
    run_gpu(context(), find_method("naive"), scene.color, scene.depth_m, lens, find_method("naive").defaults(pattern),
            &passes);
    ASSERT_EQ(passes.size(), 2u);
    coc_ms.push_back(passes[0].ms);
    gather_ms.push_back(passes[1].ms);
  }
  std::sort(coc_ms.begin(), coc_ms.end());
  std::sort(gather_ms.begin(), gather_ms.end());
  EXPECT_GT(gather_ms[0], coc_ms[0]) << "fastest coc " << coc_ms[0] << " ms, gather " << gather_ms[0] << " ms";
}

}  // namespace
}  // namespace bokeh
