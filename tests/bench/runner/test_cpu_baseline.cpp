// figure9's CPU baseline (bench/runner/cpu_baseline.hpp): cv::filter2D with the pattern's largest disc,
// against a direct convolution in double precision whose taps are found here from the pattern's
// definition (integer offsets i k, j k with (i k)^2 + (j k)^2 <= (n k)^2), not from the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "cpu_baseline.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

struct Tap {
  int dx_px, dy_px;
};

// The lattice offsets inside the disc of radius n k: integers throughout, so exact.
std::vector<Tap> disc_taps(const GatherPattern& p) {
  const int n = p.half(), k = p.spacing_px;
  std::vector<Tap> taps;
  for (int j = -n; j <= n; ++j)
    for (int i = -n; i <= n; ++i)
      if ((i * k) * (i * k) + (j * k) * (j * k) <= (n * k) * (n * k)) taps.push_back({i * k, j * k});
  return taps;
}

// out(x, y) = sum over the taps of colour(x + dx, y + dy) / taps, zero beyond the border: the
// exact reference's border convention (nothing comes in from outside, nothing renormalised).
std::vector<double> direct_convolution(const Image& color, const GatherPattern& p) {
  const std::vector<Tap> taps = disc_taps(p);
  const double weight = 1.0 / static_cast<double>(taps.size());
  std::vector<double> out(color.pixels.size(), 0.0);
  for (int y = 0; y < color.height; ++y)
    for (int x = 0; x < color.width; ++x)
      for (const Tap& t : taps) {
        const int sx = x + t.dx_px, sy = y + t.dy_px;
        if (sx < 0 || sy < 0 || sx >= color.width || sy >= color.height) continue;
        for (int c = 0; c < 3; ++c)
          out[(static_cast<std::size_t>(y) * color.width + x) * 3 + c] += weight * color.px(sx, sy)[c];
      }
  return out;
}

TEST(CpuBaseline, DiscKernelIsThePatternsLargestDiscAtOneOverItsArea) {
  for (const GatherPattern p : {GatherPattern{5, 1}, GatherPattern{5, 2}, GatherPattern{81, 2}, GatherPattern{9, 3}}) {
    const int side_px = baseline::disc_kernel_side_px(p);
    ASSERT_EQ(side_px, 2 * p.half() * p.spacing_px + 1);
    const std::vector<float> kernel = baseline::disc_kernel(p);
    ASSERT_EQ(kernel.size(), static_cast<std::size_t>(side_px) * side_px);
    const std::vector<Tap> taps = disc_taps(p);
    ASSERT_EQ(static_cast<int>(taps.size()), discrete_disc_area(p.max_radius_px(), p));  // FLAG's area: same taps
    std::vector<float> want(kernel.size(), 0.0f);
    const int centre = side_px / 2;
    for (const Tap& t : taps)
      want[static_cast<std::size_t>(centre + t.dy_px) * side_px + (centre + t.dx_px)] = 1.0f / static_cast<float>(taps.size());
    EXPECT_EQ(kernel, want) << "N " << p.size_n << " k " << p.spacing_px;
  }
}

// The direct path (kernels under 130 taps at f32: 5x5, 9x9) and the DFT path OpenCV takes for larger
// kernels (25x25 at N = 9, k = 3), each against the double-precision convolution.
TEST(CpuBaseline, Filter2dEqualsADirectConvolutionInDoublePrecision) {
  if (!baseline::built_with_opencv()) GTEST_SKIP() << baseline::unavailable_reason();
  const Image color = test::random_image(40, 30, 3, 0.0f, 4.0f, 44);
  for (const GatherPattern p : {GatherPattern{5, 1}, GatherPattern{5, 2}, GatherPattern{9, 3}})
    for (int threads : {1, 2}) {
      const Image got = baseline::filter2d_disc(color, p, threads);
      ASSERT_TRUE(got.same_shape(color));
      const std::vector<double> want = direct_convolution(color, p);
      // f32 rounding: each output is a weighted mean of values below 4; both paths come within about one
      // float ulp of 4 (5.7e-7 at worst here), 8 ulps (3.8e-6) is the bound. A wrong tap or border moves
      // an output by 1/taps of a value or more (BORDER_REFLECT_101 in its place: 1.6 to 1.7).
      const double tolerance = 8 * 4 * std::numeric_limits<float>::epsilon();
      double worst = 0;
      for (std::size_t i = 0; i < want.size(); ++i) worst = std::max(worst, std::abs(got.pixels[i] - want[i]));
      EXPECT_LE(worst, tolerance) << "N " << p.size_n << " k " << p.spacing_px << ", " << threads << " threads";
    }
}

TEST(CpuBaseline, WithoutOpenCvSaysSo) {
  if (baseline::built_with_opencv()) {
    EXPECT_EQ(baseline::unavailable_reason(), "");
    EXPECT_FALSE(baseline::opencv_version().empty());
    return;
  }
  EXPECT_NE(baseline::unavailable_reason().find("not built with OpenCV"), std::string::npos);
  EXPECT_THROW(baseline::filter2d_disc(Image(4, 4, 3), GatherPattern{3, 1}, 1), std::runtime_error);
}

}  // namespace
}  // namespace bokeh
