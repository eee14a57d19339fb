// CPU references: naive gather and FLAG agree, radius 0 is the identity, energy is conserved.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "coc.hpp"
#include "flag.hpp"
#include "naive_gather.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;

TEST(DiscreteDisc, AreaCountsPatternSamplesInsideTheDisc) {
  const GatherPattern p{41, 2};
  EXPECT_EQ(discrete_disc_area(0.0f, p), 1);
  EXPECT_EQ(discrete_disc_area(1.9f, p), 1);   // the nearest other sample is 2 px away
  EXPECT_EQ(discrete_disc_area(2.0f, p), 5);   // +-2 on both axes
  EXPECT_EQ(discrete_disc_area(2.9f, p), 9);   // (2,2) is 2.83 px away
  // Large radii approach pi r^2 / k^2 (Gauss circle problem: error O(r/k)).
  const float r = 40.0f;
  EXPECT_NEAR(discrete_disc_area(r, p), M_PI * r * r / 4.0, 2.0 * M_PI * r / 2.0);
}

TEST(DiscreteDisc, ReachLayerMatchesDiscTestExactly) {
  for (float r = 0.0f; r < 20.0f; r += 0.37f)
    for (int dx = 0; dx <= 20; dx += 2) {
      const int z = disc_reach_layer(r * r, dx, 2, 10);
      for (int zz = 0; zz <= 10; ++zz) EXPECT_EQ(zz <= z, in_disc(r * r, dx, zz * 2)) << r << " " << dx << " " << zz;
    }
}

TEST(CpuReferences, RadiusZeroIsTheIdentity) {
  const Image color = random_image(23, 17, 3, 0.0f, 5.0f, 1);
  const Image radius(23, 17, 1, 0.0f);
  for (const GatherPattern& p : {GatherPattern{9, 2}, GatherPattern{5, 1}}) {
    const Image packed = pack_gather_input(color, radius, p);
    for (const Image& out : {naive_gather(packed, p, 2), flag_blur(packed, p, LayerPrecision::f32, 2)})
      for (std::size_t i = 0; i < color.pixels.size(); ++i) ASSERT_EQ(out.pixels[i], color.pixels[i]);
  }
}

// Each source spreads colour / area over exactly `area` outputs, so with every disc inside the
// image the output's total equals the input's (up to float summation).
TEST(CpuReferences, EnergyIsConservedAwayFromBorders) {
  const GatherPattern p{11, 2};  // max radius 10 px
  const int w = 64, h = 48, margin = 11;
  Image color = random_image(w, h, 3, 0.0f, 4.0f, 2);
  const Image radius = random_image(w, h, 1, 0.0f, p.max_radius_px(), 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (x < margin || y < margin || x >= w - margin || y >= h - margin)
        for (int c = 0; c < 3; ++c) color.px(x, y)[c] = 0.0f;
  const Image packed = pack_gather_input(color, radius, p);
  auto rgb_sum = [](const Image& img) { return channel_sum(img, 0) + channel_sum(img, 1) + channel_sum(img, 2); };
  const double in = rgb_sum(color);
  EXPECT_NEAR(rgb_sum(naive_gather(packed, p, 2)) / in, 1.0, 1e-5);
  EXPECT_NEAR(rgb_sum(flag_blur(packed, p, LayerPrecision::f32, 2)) / in, 1.0, 1e-5);
}

TEST(CpuReferences, ConstantImageAtConstantRadiusStaysConstantInside) {
  const GatherPattern p{9, 2};
  const Image color(40, 40, 3, 2.5f);
  const Image radius(40, 40, 1, 7.3f);
  const Image out = naive_gather(pack_gather_input(color, radius, p), p, 2);
  for (int y = 8; y < 32; ++y)
    for (int x = 8; x < 32; ++x) ASSERT_NEAR(out.px(x, y)[1], 2.5f, 1e-5f);
}

TEST(CpuReferences, FlagEqualsNaiveGather) {
  const GatherPattern p{13, 2};
  const Image color = random_image(50, 37, 3, 0.0f, 10.0f, 4);
  const Image radius = random_image(50, 37, 1, 0.0f, p.max_radius_px(), 5);
  const Image packed = pack_gather_input(color, radius, p);
  const Image naive = naive_gather(packed, p, 2), flag = flag_blur(packed, p, LayerPrecision::f32, 2);
  for (std::size_t i = 0; i < naive.pixels.size(); ++i)
    ASSERT_NEAR(flag.pixels[i], naive.pixels[i], 3e-6f * std::max(1.0f, naive.pixels[i]));
}

TEST(CpuReferences, PointLightMakesADiscOfItsRadius) {
  const GatherPattern p{21, 1};
  Image color(41, 41, 3, 0.0f);
  Image radius(41, 41, 1, 0.0f);
  color.px(20, 20)[0] = 100.0f;
  *radius.px(20, 20) = 6.5f;
  const Image out = naive_gather(pack_gather_input(color, radius, p), p, 2);
  int lit = 0;
  for (int y = 0; y < 41; ++y)
    for (int x = 0; x < 41; ++x) {
      const bool inside = (x - 20) * (x - 20) + (y - 20) * (y - 20) <= 6.5 * 6.5;
      EXPECT_EQ(out.px(x, y)[0] > 0.0f, inside) << x << "," << y;
      lit += inside;
    }
  EXPECT_NEAR(out.px(20, 20)[0], 100.0f / lit, 1e-4f);
}

}  // namespace
}  // namespace bokeh
