// The exact scatter reference against truths computed independently: energy bookkeeping, pi r^2,
// numerically integrated disc/square overlaps, and depth-ordered cases small enough to work by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>

#include "coc.hpp"
#include "exact_scatter.hpp"
#include "image_io.hpp"
#include "scene.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;
using bokeh::test::channel_sum;  // overloads the local std::vector<double> version below

constexpr double kPi = std::numbers::pi;

double channel_sum(const std::vector<double>& rgb, int k) {
  double s = 0.0;
  for (std::size_t i = k; i < rgb.size(); i += 3) s += rgb[i];
  return s;
}

// Area of the disc of radius r (centre = pixel centre) inside the unit square at offset (dx, dy), by
// midpoint integration over x of the chord's overlap with [dy-0.5, dy+0.5]: independent of the
// analytic formula, accurate to ~1e-7 with this many steps (the integrand is Hoelder-1/2 at x = +-r).
double integrated_coverage(double r, int dx, int dy) {
  constexpr int kSteps = 200000;
  double area = 0.0;
  for (int i = 0; i < kSteps; ++i) {
    const double x = dx - 0.5 + (i + 0.5) / kSteps;
    if (std::abs(x) >= r) continue;
    const double half = std::sqrt(r * r - x * x);
    area += std::max(0.0, std::min(dy + 0.5, half) - std::max(dy - 0.5, -half)) / kSteps;
  }
  return area;
}

TEST(ExactScatter, RadiusZeroIsTheIdentityInBothModes) {
  const Image color = random_image(17, 11, 3, 0.0f, 8.0f, 1);
  const Image depth = random_image(17, 11, 1, 0.5f, 50.0f, 2);
  Image radius = random_image(17, 11, 1, 0.0f, 0.5f, 3);  // every disc inside its own pixel
  radius.pixels[0] = 0.0f;
  for (ScatterComposite mode : {ScatterComposite::energy_sum, ScatterComposite::depth_ordered}) {
    const Image out = exact_scatter(color, radius, depth, mode, 3);
    ASSERT_TRUE(out.same_shape(color)) << to_string(mode);
    for (std::size_t i = 0; i < color.pixels.size(); ++i)
      ASSERT_EQ(out.pixels[i], color.pixels[i]) << to_string(mode) << " at value " << i;
  }
}

TEST(ExactScatter, EnergySumConservesEnergyAwayFromBorders) {
  constexpr int kW = 64, kH = 48, kMargin = 12;
  constexpr float kMaxRadius = 11.0f;  // reach = ceil(11.5) - 1 = 11 < margin: nothing leaves the image
  Image color(kW, kH, 3);
  const Image noise = random_image(kW, kH, 3, 0.0f, 5.0f, 4);
  for (int y = kMargin; y < kH - kMargin; ++y)
    for (int x = kMargin; x < kW - kMargin; ++x)
      for (int k = 0; k < 3; ++k) color.px(x, y)[k] = noise.px(x, y)[k];
  const Image radius = random_image(kW, kH, 1, 0.0f, kMaxRadius, 5);
  const std::vector<double> out = exact_scatter_double(color, radius, Image(), ScatterComposite::energy_sum, 2);
  for (int k = 0; k < 3; ++k) {
    const double in_sum = channel_sum(color, k);
    EXPECT_NEAR(channel_sum(out, k), in_sum, 1e-9 * in_sum) << "channel " << k;
  }
  // The float image only adds per-pixel rounding.
  const Image out_float = exact_scatter(color, radius, Image(), ScatterComposite::energy_sum, 2);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(channel_sum(out_float, k), channel_sum(color, k), 1e-6 * channel_sum(color, k));
}

// Fully defocused, one radius everywhere: every target in the interior (the radius, rounded up, in
// from each side) receives a whole disc's worth of in-frame sources, so a uniform image stays uniform
// there in both modes; toward the border it darkens, the light beyond it never having existed.
TEST(ExactScatter, UniformImageFullyDefocusedStaysUniformInTheInterior) {
  constexpr int kW = 40, kH = 32;
  constexpr float kRadius = 7.3f;
  const int margin = static_cast<int>(std::ceil(kRadius));
  const Image color(kW, kH, 3, 2.0f);
  for (ScatterComposite mode : {ScatterComposite::energy_sum, ScatterComposite::depth_ordered}) {
    const std::vector<double> out = exact_scatter_double(color, Image(kW, kH, 1, kRadius), Image(kW, kH, 1, 10.0f), mode, 2);
    for (int y = margin; y < kH - margin; ++y)
      for (int x = margin; x < kW - margin; ++x)
        ASSERT_NEAR(out[(static_cast<std::size_t>(y) * kW + x) * 3], 2.0, 1e-9) << to_string(mode) << " " << x << "," << y;
    if (mode == ScatterComposite::energy_sum) {
      EXPECT_LT(out[0], 2.0 * 0.5);  // a corner keeps about a quarter
    }
  }
}

TEST(ExactScatter, UnitPointSpreadsToADiscOfAreaPiRSquared) {
  constexpr int kSize = 31, kC = kSize / 2;
  for (float r : {0.75f, 1.0f, 1.5f, 2.3f, 3.0f, 4.75f, 7.5f, 10.0f, 13.2f}) {
    SCOPED_TRACE(::testing::Message() << "radius " << r);
    Image color(kSize, kSize, 3);
    color.px(kC, kC)[0] = 1.0f;
    const std::vector<double> out =
        exact_scatter_double(color, Image(kSize, kSize, 1, r), Image(), ScatterComposite::energy_sum, 2);
    EXPECT_NEAR(channel_sum(out, 0), 1.0, 1e-12);
    // The centre square lies wholly inside the disc (coverage 1), so its share is 1 / area: the sum of
    // the analytic coverages must be pi r^2 (the coverage is exact up to rounding: 1e-12 relative).
    const double area = 1.0 / out[(kC * kSize + kC) * 3];
    EXPECT_NEAR(area, kPi * r * r, 1e-12 * kPi * r * r);
    int covered = 0, expected_covered = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const int dx = std::abs(x - kC), dy = std::abs(y - kC);
        const double share = out[(y * kSize + x) * 3];
        // Support: squares whose nearest point is strictly inside the disc.
        const double nx = std::max(dx - 0.5, 0.0), ny = std::max(dy - 0.5, 0.0);
        expected_covered += nx * nx + ny * ny < static_cast<double>(r) * r;
        covered += share > 0.0;
        // Squares wholly inside get exactly 1 / area; every square's coverage matches integration.
        if ((dx + 0.5) * (dx + 0.5) + (dy + 0.5) * (dy + 0.5) <= static_cast<double>(r) * r)
          ASSERT_EQ(share, out[(kC * kSize + kC) * 3]) << x << "," << y;
        else if (nx * nx + ny * ny >= static_cast<double>(r) * r)
          ASSERT_EQ(share, 0.0) << x << "," << y;
        else
          ASSERT_NEAR(share * kPi * r * r, integrated_coverage(r, dx, dy), 2e-6) << x << "," << y;
        EXPECT_EQ(out[(y * kSize + x) * 3 + 1], 0.0);
      }
    EXPECT_EQ(covered, expected_covered);
  }
}

TEST(ExactScatter, ContributionsLeavingTheImageAreLost) {
  Image color(9, 9, 3);
  color.px(0, 0)[2] = 1.0f;
  const std::vector<double> out =
      exact_scatter_double(color, Image(9, 9, 1, 4.0f), Image(), ScatterComposite::energy_sum, 1);
  // Only the squares inside the image keep their shares: their integrated coverages over pi r^2.
  double kept = 0.0;
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x) kept += integrated_coverage(4.0, x, y);
  EXPECT_NEAR(channel_sum(out, 2), kept / (kPi * 16.0), 1e-6);
  EXPECT_LT(channel_sum(out, 2), 0.5);
}

TEST(ExactScatter, ResultsDoNotDependOnThreadCount) {
  const Image color = random_image(40, 30, 3, 0.0f, 2.0f, 6);
  const Image radius = random_image(40, 30, 1, 0.0f, 6.0f, 7);
  const Image depth = random_image(40, 30, 1, 1.0f, 4.0f, 8);
  for (ScatterComposite mode : {ScatterComposite::energy_sum, ScatterComposite::depth_ordered}) {
    const std::vector<double> one = exact_scatter_double(color, radius, depth, mode, 1);
    EXPECT_EQ(one, exact_scatter_double(color, radius, depth, mode, 5)) << to_string(mode);
  }
}

// A 15x15 in-focus backdrop (radius 0, colour b) and one source of colour c and radius 3 at the centre.
struct PointOverBackdrop {
  static constexpr int kSize = 15, kC = 7;
  static constexpr float kRadius = 3.0f;
  static constexpr float kB[3] = {0.25f, 0.375f, 0.5f}, kColor[3] = {5.0f, 4.0f, 3.0f};  // exact in float and double
  Image color{kSize, kSize, 3}, radius{kSize, kSize, 1}, depth{kSize, kSize, 1};
  PointOverBackdrop(float point_depth_m, float backdrop_depth_m) {
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        for (int k = 0; k < 3; ++k) color.px(x, y)[k] = kB[k];
        *depth.px(x, y) = backdrop_depth_m;
      }
    for (int k = 0; k < 3; ++k) color.px(kC, kC)[k] = kColor[k];
    *depth.px(kC, kC) = point_depth_m;
    *radius.px(kC, kC) = kRadius;
  }
};

TEST(ExactScatterDepthOrdered, SharpForegroundHidesABlurredSourceBehindIt) {
  // Every backdrop pixel is in front and in focus: it fills its own view, so nothing of the blurred source
  // shows beside it, and the source's own pixel sees only the source.
  const PointOverBackdrop s(10.0f, 1.0f);
  const Image out = exact_scatter(s.color, s.radius, s.depth, ScatterComposite::depth_ordered, 2);
  for (std::size_t i = 0; i < out.pixels.size(); ++i)
    ASSERT_NEAR(out.pixels[i], s.color.pixels[i], 1e-6 * s.color.pixels[i]) << "value " << i;
}

TEST(ExactScatterDepthOrdered, BlurredForegroundIsCompositedOverTheBackdrop) {
  using P = PointOverBackdrop;
  const P s(1.0f, 10.0f);
  const std::vector<double> out = exact_scatter_double(s.color, s.radius, s.depth, ScatterComposite::depth_ordered, 2);
  // The source's share w(t) of each target, from a lone unit point under energy_sum.
  Image unit(P::kSize, P::kSize, 3);
  unit.px(P::kC, P::kC)[0] = 1.0f;
  const std::vector<double> share = exact_scatter_double(unit, s.radius, Image(), ScatterComposite::energy_sum, 1);
  const double w_centre = 1.0 / (kPi * P::kRadius * P::kRadius);  // centre square wholly inside the disc
  ASSERT_NEAR(share[(P::kC * P::kSize + P::kC) * 3], w_centre, 1e-15);
  for (int k = 0; k < 3; ++k) {
    double total = 0.0;
    for (int y = 0; y < P::kSize; ++y)
      for (int x = 0; x < P::kSize; ++x) {
        const std::size_t i = (static_cast<std::size_t>(y) * P::kSize + x) * 3;
        const double w = share[i];
        // Near first: c w over the backdrop pixel, which fills the rest (1 - w) of the view. The backdrop
        // behind the source's own pixel is hidden and in focus (reaches nothing): that view stays dark.
        const double expected = x == P::kC && y == P::kC ? P::kColor[k] * w : P::kColor[k] * w + P::kB[k] * (1.0 - w);
        ASSERT_NEAR(out[i + k], expected, 1e-12) << x << "," << y << " channel " << k;
        total += out[i + k];
      }
    // By hand: all of c, and the backdrop's (N - 1) b less the share 1 - 1 / (9 pi) the source hides.
    const double hand = (P::kSize * P::kSize - 1) * P::kB[k] + P::kColor[k] - P::kB[k] * (1.0 - w_centre);
    EXPECT_NEAR(total, hand, 1e-10) << "channel " << k;
  }
  // energy_sum instead adds the spread colour on top of the backdrop: (N - 1) b + c.
  const std::vector<double> summed = exact_scatter_double(s.color, s.radius, s.depth, ScatterComposite::energy_sum, 1);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(channel_sum(summed, k), (P::kSize * P::kSize - 1) * P::kB[k] + P::kColor[k], 1e-10);
}

TEST(ExactScatterDepthOrdered, OpaqueBlurredSurfaceHidesWhatIsBehind) {
  // Left half: a near surface of colour c blurred with radius 3. Right half: a far in-focus surface b.
  constexpr int kW = 32, kH = 16, kSplit = 16;
  const float c[3] = {2.0f, 1.0f, 0.5f}, b[3] = {0.1f, 0.6f, 0.3f};
  Image color(kW, kH, 3), radius(kW, kH, 1), depth(kW, kH, 1), near_mask(kW, kH, 3), ones(kW, kH, 3, 1.0f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool near = x < kSplit;
      for (int k = 0; k < 3; ++k) color.px(x, y)[k] = near ? c[k] : b[k];
      *radius.px(x, y) = near ? 3.0f : 0.0f;
      *depth.px(x, y) = near ? 1.0f : 8.0f;
      near_mask.px(x, y)[0] = near ? 1.0f : 0.0f;
    }
  const std::vector<double> out = exact_scatter_double(color, radius, depth, ScatterComposite::depth_ordered, 2);
  // F(t): how much of target t's view the near surface fills = its summed shares. in_image(t): the share
  // of a radius-3 disc around t inside the image (the rest, off-image, the near surface continues into).
  const std::vector<double> fill = exact_scatter_double(near_mask, radius, Image(), ScatterComposite::energy_sum, 2);
  const std::vector<double> in_image =
      exact_scatter_double(ones, Image(kW, kH, 1, 3.0f), Image(), ScatterComposite::energy_sum, 2);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * kW + x) * 3;
      for (int k = 0; k < 3; ++k) {
        // Left: only the near surface, extended past the border; what lies behind its edge is hidden and
        // in focus, so that part of the view stays dark. Right: near surface first, the far pixel fills the rest.
        const double expected =
            x < kSplit ? c[k] * (fill[i] + 1.0 - in_image[i]) : c[k] * fill[i] + b[k] * (1.0 - fill[i]);
        ASSERT_NEAR(out[i + k], expected, 1e-12) << x << "," << y;
      }
      if (x >= kSplit + 3) {
        ASSERT_EQ(fill[i], 0.0);  // beyond the blur's reach the far surface is untouched
      }
    }
  // Inside the near surface, away from the borders, the shares of one surface add up to a full view:
  // nothing behind leaks through (a multiplicative "over" of the pieces would let e^-1 through).
  EXPECT_NEAR(fill[(8 * kW + 8) * 3], 1.0, 1e-12);
}

TEST(ExactScatterDepthOrdered, BlurredBackgroundContinuesBehindNearerPixelsAndBeyondTheBorder) {
  // Left: a near in-focus surface c. Right: a far surface b blurred with radius 3. The far surface's
  // discs are cut where the near surface and the border hide them; continuing it there restores a full
  // view, so the output is the input: no dark halo around the near surface, no darkened border.
  constexpr int kW = 24, kH = 12, kSplit = 10;
  Image color(kW, kH, 3), radius(kW, kH, 1), depth(kW, kH, 1);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool near = x < kSplit;
      const float rgb[3] = {near ? 1.5f : 0.25f, near ? 0.5f : 0.75f, 0.125f};
      std::copy(rgb, rgb + 3, color.px(x, y));
      *radius.px(x, y) = near ? 0.0f : 3.0f;
      *depth.px(x, y) = near ? 2.0f : 30.0f;
    }
  const std::vector<double> out = exact_scatter_double(color, radius, depth, ScatterComposite::depth_ordered, 2);
  for (std::size_t i = 0; i < out.size(); ++i) ASSERT_NEAR(out[i], color.pixels[i], 1e-12) << "value " << i;
  // A single blurred surface filling the frame is its own colour everywhere, borders included.
  const Image flat(kW, kH, 3, 0.75f);
  const std::vector<double> flat_out =
      exact_scatter_double(flat, Image(kW, kH, 1, 4.5f), Image(kW, kH, 1, 9.0f), ScatterComposite::depth_ordered, 2);
  for (double v : flat_out) ASSERT_NEAR(v, 0.75, 1e-12);
}

TEST(ExactScatter, RejectsBadInputs) {
  const Image color(8, 8, 3), depth(8, 8, 1, 2.0f);
  Image radius(8, 8, 1);
  EXPECT_THROW(exact_scatter(color, Image(8, 7, 1), depth, ScatterComposite::energy_sum), std::invalid_argument);
  EXPECT_THROW(exact_scatter(Image(8, 8, 2), radius, depth, ScatterComposite::energy_sum), std::invalid_argument);
  EXPECT_THROW(exact_scatter(color, radius, Image(), ScatterComposite::depth_ordered), std::invalid_argument);
  radius.pixels[5] = -1.0f;
  EXPECT_THROW(exact_scatter(color, radius, depth, ScatterComposite::energy_sum), std::invalid_argument);
  radius.pixels[5] = NAN;
  EXPECT_THROW(exact_scatter(color, radius, depth, ScatterComposite::energy_sum), std::invalid_argument);
  Image bad_depth = depth;
  bad_depth.pixels[3] = INFINITY;
  EXPECT_THROW(exact_scatter(color, Image(8, 8, 1), bad_depth, ScatterComposite::depth_ordered), std::invalid_argument);
}

TEST(ExactReferenceCache, StoresOnceAndReadsBackTheSameImage) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bokeh-reference-cache-test-" + std::to_string(std::random_device{}()));
  ExactReferenceCache cache(dir);
  const Image color = random_image(20, 14, 3, 0.0f, 30.0f, 9);
  Image radius = random_image(20, 14, 1, 0.0f, 4.0f, 10);
  const Image depth = random_image(20, 14, 1, 1.0f, 9.0f, 11);
  const auto path = cache.path_for(color, radius, depth, ScatterComposite::depth_ordered);
  EXPECT_FALSE(std::filesystem::exists(path));
  const Image first = cache.get(color, radius, depth, ScatterComposite::depth_ordered, 2);
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);  // no temporary left behind
  EXPECT_EQ(first.pixels, exact_scatter(color, radius, depth, ScatterComposite::depth_ordered, 2).pixels);
  EXPECT_EQ(cache.get(color, radius, depth, ScatterComposite::depth_ordered, 2).pixels, first.pixels);
  // Any input bit, or the mode, names another file; energy_sum ignores depth.
  EXPECT_NE(cache.path_for(color, radius, depth, ScatterComposite::energy_sum), path);
  EXPECT_EQ(cache.path_for(color, radius, depth, ScatterComposite::energy_sum),
            cache.path_for(color, radius, Image(), ScatterComposite::energy_sum));
  radius.pixels[17] = std::nextafter(radius.pixels[17], 100.0f);
  EXPECT_NE(cache.path_for(color, radius, depth, ScatterComposite::depth_ordered), path);
  std::filesystem::remove_all(dir);
}

// An entry replaced by another valid entry (or one whose pixels were edited) is recomputed with a note,
// never used: the reference returned is the cold run's.
TEST(ExactReferenceCache, AnEntryThatIsNotItsKeysIsRecomputedWithANote) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bokeh-reference-cache-swap-" + std::to_string(std::random_device{}()));
  ExactReferenceCache cache(dir);
  const Image color_a = random_image(16, 12, 3, 0.0f, 30.0f, 21), color_b = random_image(16, 12, 3, 0.0f, 30.0f, 22);
  const Image radius = random_image(16, 12, 1, 0.0f, 3.0f, 23), depth = random_image(16, 12, 1, 1.0f, 9.0f, 24);
  const auto mode = ScatterComposite::energy_sum;
  const Image cold_a = exact_scatter(color_a, radius, depth, mode, 2);
  cache.get(color_a, radius, depth, mode, 2);
  cache.get(color_b, radius, depth, mode, 2);
  const auto path_a = cache.path_for(color_a, radius, depth, mode), path_b = cache.path_for(color_b, radius, depth, mode);
  std::filesystem::copy_file(path_b, path_a, std::filesystem::copy_options::overwrite_existing);
  testing::internal::CaptureStderr();
  EXPECT_EQ(cache.get(color_a, radius, depth, mode, 2).pixels, cold_a.pixels);
  const std::string note = testing::internal::GetCapturedStderr();
  EXPECT_NE(note.find("note: reference cache entry '" + path_a.string() + "' was computed for other inputs"),
            std::string::npos) << note;
  EXPECT_EQ(std::count(note.begin(), note.end(), '\n'), 1) << note;
  // Rewritten: the next read uses it silently.
  testing::internal::CaptureStderr();
  EXPECT_EQ(cache.get(color_a, radius, depth, mode, 2).pixels, cold_a.pixels);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  // The right key over other pixels (an edited entry): the pixel hash catches it.
  Image edited = cold_a;
  edited.pixels[7] += 1.0f;
  const std::string stem = path_a.stem().string(), key = stem.substr(stem.rfind('-') + 1);
  write_image(edited, path_a.string(), {{"bokehReferenceKey", key}});
  testing::internal::CaptureStderr();
  EXPECT_EQ(cache.get(color_a, radius, depth, mode, 2).pixels, cold_a.pixels);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("do not match the hash"), std::string::npos);
  // An image with no key (another tool's, or an older bokehbench's) is not trusted either.
  write_image(cold_a, path_a.string());
  testing::internal::CaptureStderr();
  EXPECT_EQ(cache.get(color_a, radius, depth, mode, 2).pixels, cold_a.pixels);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("carries no key"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// Timing of the size sweeps use: run with --gtest_also_run_disabled_tests --gtest_filter='*Timing*'.
}  // namespace
}  // namespace bokeh
