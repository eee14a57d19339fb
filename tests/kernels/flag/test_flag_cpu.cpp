// CPU references: naive gather and FLAG agree, radius 0 is the identity, energy is conserved; the
// disc index and area table against in_disc; the fast references against the straightforward ones.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

#include "coc.hpp"
#include "flag.hpp"
#include "naive_gather.hpp"
#include "run.hpp"
#include "scene.hpp"
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

// Radii at which a pattern's discrete disc changes: r^2 just below, at and just above every squared
// lattice distance (i^2 + j^2) k^2 of the pattern, plus radii beyond its largest circle.
std::vector<float> threshold_radii(const GatherPattern& p) {
  std::set<long long> distances;
  for (int j = 0; j <= p.half(); ++j)
    for (int i = j; i <= p.half(); ++i) distances.insert(static_cast<long long>(i * i + j * j) * p.spacing_px * p.spacing_px);
  std::vector<float> radii = {0.0f, 1e-30f, p.max_radius_px() * 1.5f, 1e6f};
  for (long long d : distances) {
    const float r = std::sqrt(static_cast<float>(d));
    radii.insert(radii.end(), {std::nextafter(r, 0.0f), r, std::nextafter(r, 1e38f)});
  }
  return radii;
}

// The area table and the disc index reproduce the O(N) count and in_disc for every radius at which
// the disc changes, for every odd N up to 201 at k = 2, and for N = 201 at k = 1, 3 and 64 (where r^2
// passes 2^24 and float(dx^2 + dy^2) rounds: the threshold's ties-to-even branch).
TEST(DiscreteDisc, AreaTableEqualsTheCountForEveryRadiusUpToTheLargestPattern) {
  std::vector<GatherPattern> patterns;
  for (int n = 1; n <= 201; n += 2) patterns.push_back({n, 2});
  for (int k : {1, 3, 64}) patterns.push_back({201, k});
  long long checked = 0;
  for (const GatherPattern& p : patterns) {
    const DiscAreaTable table(p);
    for (float r : threshold_radii(p)) {
      ASSERT_EQ(table.area(r), discrete_disc_area(r, p)) << "N " << p.size_n << " k " << p.spacing_px << " r " << r;
      ++checked;
    }
  }
  EXPECT_EQ(DiscAreaTable({201, 2}).area(0.0f), 1);
  EXPECT_EQ(DiscAreaTable({201, 2}).area(1e9f), 201 * 201);
  EXPECT_EQ(DiscAreaTable({41, 2}).area(std::nanf("")), 0);  // like the count: a NaN disc holds nothing
  EXPECT_GT(checked, 400000);  // radii checked over all patterns
}

// The share of the largest disc inside the frame, against a count over every pixel and every pattern
// offset (in_disc at the largest radius, the sample's position inside the frame): patterns smaller
// than, as large as and larger than the frame, on both axes.
TEST(DiscreteDisc, ShareInFrameEqualsACountOverEveryPixel) {
  for (const auto& [p, w, h] : {std::tuple{GatherPattern{9, 2}, 37, 23}, std::tuple{GatherPattern{21, 3}, 40, 17},
                                std::tuple{GatherPattern{41, 2}, 24, 90}, std::tuple{GatherPattern{1, 2}, 5, 4}}) {
    const float r2 = p.max_radius_px() * p.max_radius_px();
    long inside = 0, taps = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int j = -p.half(); j <= p.half(); ++j)
          for (int i = -p.half(); i <= p.half(); ++i) {
            if (!in_disc(r2, i * p.spacing_px, j * p.spacing_px)) continue;
            ++taps;
            const int sx = x + i * p.spacing_px, sy = y + j * p.spacing_px;
            inside += sx >= 0 && sx < w && sy >= 0 && sy < h;
          }
    EXPECT_NEAR(disc_share_in_frame(p, w, h), static_cast<double>(inside) / taps, 1e-12)
        << "N " << p.size_n << " k " << p.spacing_px << " frame " << w << "x" << h;
  }
  EXPECT_EQ(disc_share_in_frame({1, 2}, 800, 600), 1.0);  // a pixel's own sample is always inside
}

TEST(DiscreteDisc, DiscIndexAndReachMatchInDisc) {
  std::mt19937 rng(11);
  for (int k : {1, 2, 3, 7, 64}) {
    const GatherPattern p{201, k};
    const int n = p.half();
    std::vector<float> radii = threshold_radii(p);
    std::shuffle(radii.begin(), radii.end(), rng);
    radii.resize(std::min<std::size_t>(radii.size(), 3000));
    for (float r : radii) {
      const float r2 = r * r;
      const int index = disc_index(r2, k, 2 * n * n);
      for (int j = 0; j <= n; j += 1 + j / 8)
        for (int i = 0; i <= n; i += 1 + i / 8) {
          ASSERT_EQ(i * i + j * j <= index, in_disc(r2, i * k, j * k)) << "k " << k << " r " << r << " i " << i << " j " << j;
          ASSERT_EQ(reach_layer(index, i, n), disc_reach_layer(r2, i * k, k, n)) << "k " << k << " r " << r << " i " << i;
        }
    }
  }
}

// The scenes the harness renders, packed by the CPU CoC pass, at sizes that leave partial vectors
// and strips, with patterns whose discs cross the borders.
struct PackedScene {
  std::string name;
  GatherPattern pattern;
  Image packed;
};
std::vector<PackedScene> packed_scenes() {
  std::vector<PackedScene> out;
  const GatherPattern patterns[] = {{1, 2}, {9, 2}, {7, 3}, {11, 1}, {41, 2}};
  for (const std::string name : {"hoops", "pillars", "points"})
    for (const GatherPattern& p : patterns) {
      const Scene s = make_scene(name, 61, 43);
      const Lens lens = with_max_coc_radius(s.lens, s.depth_m, p.max_radius_px() * 1.2);
      out.push_back({name, p, cpu_coc_pass(s.color, s.depth_m, lens, p, 2).packed});
    }
  return out;
}

TEST(CpuReferences, VectorisedNaiveGatherEqualsTheReferenceBitForBit) {
  for (const PackedScene& s : packed_scenes())
    for (int threads : {1, 2})
      EXPECT_TRUE(same_bits(naive_gather(s.packed, s.pattern, threads), naive_gather_reference(s.packed, s.pattern, 1)))
          << s.name << " N " << s.pattern.size_n << " k " << s.pattern.spacing_px << " threads " << threads;
}

TEST(CpuReferences, StripFlagEqualsTheReferenceBitForBit) {
  for (const PackedScene& s : packed_scenes())
    for (LayerPrecision precision : all_layer_precisions())
      for (int threads : {1, 3})
        EXPECT_TRUE(same_bits(flag_blur(s.packed, s.pattern, precision, threads),
                              flag_blur_reference(s.packed, s.pattern, precision, 1)))
            << s.name << " N " << s.pattern.size_n << " k " << s.pattern.spacing_px << " " << to_string(precision)
            << " threads " << threads;
}

// The scan binning's layers (flag_horizontal_scan, the GPU's order) against flag_horizontal's
// ordered sums, f32. Both sum the same samples per (pixel, layer). A value of the scan passes through
// at most E + T roundings (E <= 2 (T + 2 n) events added into the segment's difference array, T prefix
// additions), each partial sum at most the sum of |events| <= 2 S, S = sum of |s| over the segment's
// samples that reach the layer; the ordered one through at most N + n roundings of partial sums <= S.
// So |scan - ordered| <= u (2 (E + T) + N + n) S, u = 2^-24. Segments of 1 column, a few, and the
// GPU's (one per row and phase at these widths).
TEST(CpuReferences, ScanLayersStayWithinTheirSummationBoundOfTheOrderedOnes) {
  const double u = std::ldexp(1.0, -24);
  double worst_ratio = 0;  // largest |scan - ordered| / (u S) seen
  for (const PackedScene& s : packed_scenes())
    for (int segment : {1, 5, 16, kFlagScanSegment}) {
      const FlagLayers ordered = flag_horizontal(s.packed, s.pattern, LayerPrecision::f32, 2);
      const FlagLayers scan = flag_horizontal_scan(s.packed, s.pattern, LayerPrecision::f32, segment, 2);
      const int n = s.pattern.half(), k = s.pattern.spacing_px, w = s.packed.width;
      const double roundings = 2.0 * (2 * (segment + 2 * n) + segment) + s.pattern.size_n + n;
      for (int y = 0; y < s.packed.height; ++y)
        for (int x = 0; x < w; ++x)
          for (int z = 0; z <= n; ++z) {
            const int x0 = x % k + (x / k) / segment * segment * k;  // the segment's first column
            double sum[3] = {0, 0, 0};
            for (int j = -n; j < segment + n; ++j) {
              const int sx = x0 + j * k;
              if (sx < 0 || sx >= w) continue;
              const float* src = s.packed.px(sx, y);
              if (disc_index(src[3] * src[3], k, 2 * n * n) < z * z) continue;
              for (int c = 0; c < 3; ++c) sum[c] += std::abs(double(src[c]));
            }
            for (int c = 0; c < 3; ++c) {
              const double error = std::abs(double(scan.at(x, y, z)[c]) - ordered.at(x, y, z)[c]);
              if (sum[c] > 0) worst_ratio = std::max(worst_ratio, error / (u * sum[c]));
              ASSERT_LE(error, u * roundings * sum[c])
                  << s.name << " N " << s.pattern.size_n << " k " << k << " segment " << segment << " at " << x << ","
                  << y << " layer " << z;
            }
          }
    }
  RecordProperty("worst_error_in_u_times_S", std::to_string(worst_ratio));
}

// Streamed through a ring of rows (the GPU's layer_buffer = streamed order, and how the method's
// reference bounds its memory past 256 MiB): flag_blur's image bit for bit, for bands of one row (the
// ring wraps every 2 n k + 1 rows), a few rows, and more rows than the image (no wrap at all).
TEST(CpuReferences, StreamedFlagEqualsTheStripFlagBitForBit) {
  for (const PackedScene& s : packed_scenes())
    for (LayerPrecision precision : {LayerPrecision::f32, LayerPrecision::f16, LayerPrecision::r11g11b10f}) {
      const Image strips = flag_blur(s.packed, s.pattern, precision, 2);
      for (int band_rows : {1, 5, 1000})
        for (int threads : {1, 3})
          EXPECT_TRUE(same_bits(flag_blur_streamed(s.packed, s.pattern, precision, band_rows, threads), strips))
              << s.name << " N " << s.pattern.size_n << " k " << s.pattern.spacing_px << " " << to_string(precision)
              << " band " << band_rows << " threads " << threads;
    }
}

TEST(CpuReferences, StreamedRefusesBracketedPrecisionsAndEmptyBands) {
  const PackedScene s = packed_scenes().front();
  EXPECT_THROW(flag_blur_streamed(s.packed, s.pattern, LayerPrecision::unorm16_bracketed, 4), std::invalid_argument);
  EXPECT_THROW(flag_blur_streamed(s.packed, s.pattern, LayerPrecision::f32, 0), std::invalid_argument);
}

TEST(CpuReferences, ScanRefusesBracketedPrecisions) {
  const PackedScene s = packed_scenes().front();
  EXPECT_THROW(flag_horizontal_scan(s.packed, s.pattern, LayerPrecision::unorm10_bracketed), std::invalid_argument);
}

// Images narrower than a vector and a strip, and one row high.
TEST(CpuReferences, FastReferencesOnTinyImages) {
  const GatherPattern p{5, 1};
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{3, 7}, std::pair{9, 1}, std::pair{70, 2}}) {
    const Image color = random_image(w, h, 3, 0.0f, 2.0f, 9);
    const Image radius = random_image(w, h, 1, 0.0f, 3.0f, 10);
    const Image packed = pack_gather_input(color, radius, p, 2);
    EXPECT_TRUE(same_bits(naive_gather(packed, p, 2), naive_gather_reference(packed, p, 1))) << w << "x" << h;
    EXPECT_TRUE(same_bits(flag_blur(packed, p, LayerPrecision::f16, 2),
                          flag_blur_reference(packed, p, LayerPrecision::f16, 1)))
        << w << "x" << h;
    EXPECT_TRUE(same_bits(flag_blur_streamed(packed, p, LayerPrecision::f16, 1, 2),
                          flag_blur_reference(packed, p, LayerPrecision::f16, 1)))
        << w << "x" << h;
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
  const Image color = random_image_in_black_border(w, h, margin, 2);
  const Image radius = random_image(w, h, 1, 0.0f, p.max_radius_px(), 3);
  const Image packed = pack_gather_input(color, radius, p);
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
