// The naive gather for any aperture (issue 23) against independent truth: the lattice offsets a light's
// shape covers, counted in double precision from the aperture's polygon, and the light it conserves.
#include <gtest/gtest.h>

#include <cmath>

#include "aperture.hpp"
#include "gpu_test_support.hpp"
#include "method.hpp"
#include "naive_shape.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

// A unit light at the centre of a 41 x 41 black frame, one radius everywhere: the output is 1 / m on
// exactly the pixels p whose offset from the light, p - centre, lies in the shape (gauge <= r), m being
// how many pattern offsets the shape holds.
TEST(NaiveShape, ALightSpreadsOverTheLatticePointsOfItsShape) {
  constexpr int kSize = 41, kC = 20;
  const GatherPattern pattern{9, 2};  // offsets up to 8 px
  constexpr float kR = 7.3f;
  for (const Aperture a : {Aperture{5, 0, 0}, Aperture{6, 0, 0}, Aperture{9, 25, 0}, Aperture{7, 0, 0.5}}) {
    SCOPED_TRACE(a.name());
    Image color(kSize, kSize, 3);
    color.px(kC, kC)[0] = 1.0f;
    const Image out = naive_shape_gather(color, Image(kSize, kSize, 1, kR), ShapeLattice(a, pattern), pattern, 1);
    int inside = 0;
    for (int j = -4; j <= 4; ++j)
      for (int i = -4; i <= 4; ++i) {
        const double g = a.gauge(2 * i, 2 * j);
        ASSERT_GT(std::abs(g - kR), 1e-4);  // no offset on the edge: float and double agree on every test
        inside += g <= kR;
      }
    double total = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const int dx = x - kC, dy = y - kC;
        const bool on_lattice = dx % 2 == 0 && dy % 2 == 0 && std::abs(dx) <= 8 && std::abs(dy) <= 8;
        const double expected = on_lattice && a.gauge(dx, dy) <= kR ? 1.0 / inside : 0.0;
        ASSERT_NEAR(out.px(x, y)[0], expected, 1e-7) << dx << "," << dy;
        total += out.px(x, y)[0];
      }
    EXPECT_NEAR(total, 1.0, 1e-6);  // the light is conserved
  }
  // A pentagon at rotation 0 points up: its vertex reaches 6 px above the light, its flat edge
  // (7.3 cos 36 deg = 5.9 px) not 6 px below.
  Image color(kSize, kSize, 3);
  color.px(kC, kC)[0] = 1.0f;
  const Image up = naive_shape_gather(color, Image(kSize, kSize, 1, kR), ShapeLattice(Aperture{5, 0, 0}, pattern), pattern, 1);
  EXPECT_GT(up.px(kC, kC - 6)[0], 0.0f);
  EXPECT_EQ(up.px(kC, kC + 6)[0], 0.0f);
}

// Every shape lies inside the disc of its radius, in the floats the gathers compare too: a radius that
// covers an offset (gauge <= r) has its disc cover it (in_disc), which the adaptive tile map relies on.
TEST(NaiveShape, EveryShapeLiesInsideItsDiscInFloats) {
  for (const GatherPattern p : {GatherPattern{41, 1}, GatherPattern{21, 3}})
    for (const char* name : {"blades5", "blades6-rot15", "blades7-rot20-curv0.5", "blades9-rot3"}) {
      const ShapeLattice lattice(parse_aperture(name), p);
      const int n = p.half(), k = p.spacing_px;
      for (int j = -n; j <= n; ++j)
        for (int i = -n; i <= n; ++i) {
          const float g = lattice.gauge[static_cast<std::size_t>(j + n) * lattice.side + (i + n)];
          ASSERT_TRUE(in_disc(g * g, i * k, j * k)) << name << " " << i << "," << j;
          // and no more than rounding above the double gauge (no shape shrunk)
          ASSERT_LE(g, parse_aperture(name).gauge(i * k, j * k) * (1 + 1e-6) + 1e-30) << name << " " << i << "," << j;
        }
    }
}

// adaptive = on for every shape: the tile map's disc bound (the largest disc that can reach a tile)
// holds every sample a shape adds, so the image is adaptive = off's, bit for bit, on the CPU and the
// GPU (and each agrees with the other within naive's bound, as conformance checks). The scenes leave
// tiles nothing blurred reaches, so the bound is used (the sample fraction is below 1).
TEST(NaiveShape, AdaptiveEqualsTheWholePatternBitForBitForEveryShape) {
  using namespace bokeh::test;
  const Method& naive = find_method("naive");
  for (const char* scene_name : {"hoops", "mostly_in_focus"}) {
    const Scene scene = make_scene(scene_name, 77, 58);
    for (const GatherPattern p : {GatherPattern{9, 2}, GatherPattern{7, 3}})
      for (const char* shape : {"blades5", "blades6", "blades6-rot15", "blades7-rot20-curv0.5", "blades9"}) {
        SCOPED_TRACE(std::string(scene_name) + " N" + std::to_string(p.size_n) + " k" + std::to_string(p.spacing_px) +
                     " " + shape);
        Lens lens = with_max_coc_radius(scene.lens, scene.depth_m, p.max_radius_px() * 1.2);
        lens.aperture = parse_aperture(shape);
        FilterOptions off = naive.defaults(p);
        off.aperture = lens.aperture;
        ASSERT_EQ(aperture_unsupported(naive, off), "");
        const Image cpu_off = run_cpu(naive, scene.color, scene.depth_m, lens, off, 2);
        const Image gpu_off = run_gpu(context(), naive, scene.color, scene.depth_m, lens, off);
        for (int tile_px : {5, 16}) {
          FilterOptions on = off;
          on.values["adaptive"] = 1;
          on.values["adaptive_tile_px"] = tile_px;
          ASSERT_EQ(aperture_unsupported(naive, on), "");
          nlohmann::json stats;
          EXPECT_TRUE(same_bits(run_cpu(naive, scene.color, scene.depth_m, lens, on, 2, &stats), cpu_off)) << tile_px;
          EXPECT_LT(stats["adaptive"]["gather_sample_fraction"].get<double>(), 1.0) << tile_px;
          std::vector<vk::PassTime> passes;
          EXPECT_TRUE(same_bits(run_gpu(context(), naive, scene.color, scene.depth_m, lens, on, &passes), gpu_off))
              << tile_px;
          std::vector<std::string> names;
          for (const auto& pass : passes) names.push_back(pass.pass);
          EXPECT_EQ(names, (std::vector<std::string>{"coc", "tile_max", "tile_reach", "shape_pack", "gather"}));
        }
      }
  }
}

}  // namespace
}  // namespace bokeh
