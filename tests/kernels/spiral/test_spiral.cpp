// spiral (kernels/spiral/): a point light of constant CoC against the closed form of a uniform disc of
// that radius; radius 0; what the blog's blend does to energy (conserved at a constant CoC, where the
// filter is a normalised convolution; not where samples stop contributing); GPU against CPU on the
// point light (the conformance suite checks the scenes).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "coc.hpp"
#include "gpu_test_support.hpp"
#include "method.hpp"
#include "run.hpp"
#include "signed_coc.hpp"
#include "spiral.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;

FilterOptions spiral_options(int n, int k, double spacing_px) {
  FilterOptions o = find_method("spiral").defaults({n, k});
  o.values["spiral_spacing_px"] = spacing_px;
  return o;
}

Image cpu_spiral(const Frame& f, const FilterOptions& o) {
  const Lens lens;
  const Image unused_packed;
  return find_method("spiral").cpu_reference({f.color, f.depth_m, lens, f.radius_px, unused_packed, o, 2});
}


TEST(SpiralSamples, FollowGodotsLoop) {
  // radius_0 = s, radius_{i+1} = radius_i + s / radius_i while < R; angle i x the golden angle.
  const double s = 0.5, r_max = 20.0;
  const auto spiral = spiral_samples(s, r_max);
  ASSERT_EQ(static_cast<std::int64_t>(spiral.size()), spiral_sample_count(s, r_max));
  double radius = s;
  for (std::size_t i = 0; i < spiral.size(); ++i) {
    const double angle = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
    EXPECT_NEAR(spiral[i].x_px + spiral[i].fx, std::cos(angle) * radius, 1e-4);
    EXPECT_NEAR(spiral[i].y_px + spiral[i].fy, std::sin(angle) * radius, 1e-4);
    EXPECT_EQ(spiral[i].x_px, std::floor(spiral[i].x_px));
    EXPECT_TRUE(spiral[i].fx >= 0.0f && spiral[i].fx < 1.0f && spiral[i].fy >= 0.0f && spiral[i].fy < 1.0f);
    EXPECT_FLOAT_EQ(spiral[i].edge_start_px, static_cast<float>(radius - 0.5));
    EXPECT_FLOAT_EQ(spiral[i].inverse_count, static_cast<float>(1.0 / (i + 2)));
    radius += s / radius;
  }
  EXPECT_GE(radius, r_max);
  // radius^2 grows by ~2s per sample: ~R^2 / (2s) samples.
  EXPECT_NEAR(static_cast<double>(spiral.size()), r_max * r_max / (2 * s), 0.02 * r_max * r_max / (2 * s));
  EXPECT_TRUE(spiral_samples(8.0, 8.0).empty());  // spacing >= R: no samples, the identity
}

// A point light at a constant CoC r: the spiral's samples are spread uniformly over the disc's area
// (radius^2 linear in the index) with equal weights, so the light spreads as a uniform disc of radius
// r: energy 1 (a normalised convolution), nothing past r + 1/2 (where the smoothstep ends) plus the
// bilinear footprint (sqrt 2), the fraction inside r / 2 is 1/4, E[d^2] = r^2 / 2 (+ 1/3: the bilinear
// tent's variance, 1/6 per axis). It is a disc of spiral-placed dots, not a filled one: how many pixels
// inside it light depends on the spacing (below).
TEST(Spiral, PointLightOfConstantCocMakesAUniformDiscOfItsRadius) {
  const int w = 128, h = 128, cx = 64, cy = 64;
  const float r = 16.0f, light = 100.0f;
  for (const double spacing : {0.5, 1.0}) {
    SCOPED_TRACE(spacing);
    Frame f = black_frame(w, h, 10.0f, r);  // all behind the focus, one CoC
    for (int c = 0; c < 3; ++c) f.color.px(cx, cy)[c] = light;
    const Image out = cpu_spiral(f, spiral_options(41, 1, spacing));  // largest radius 20 > r
    double energy = 0, inner = 0, d2 = 0, outside = 0;
    int inside_px = 0, inside_lit = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double v = out.px(x, y)[0], d = std::hypot(x - cx, y - cy);
        energy += v;
        d2 += v * d * d;
        if (d <= r / 2) inner += v;
        if (d > r + 0.5 + std::sqrt(2.0)) outside += std::abs(v);
        if (d <= r - 1.5) ++inside_px, inside_lit += v > 0;
      }
    std::printf("[spiral] s=%.1f: energy %.6f, inside r/2 %.4f (disc 0.25), E[d^2] %.2f (disc %.2f), lit %d/%d\n",
                spacing, energy / light, inner / energy, d2 / energy, r * r / 2.0 + 1.0 / 3, inside_lit, inside_px);
    EXPECT_NEAR(energy / light, 1.0, 1e-5);
    EXPECT_EQ(outside, 0.0);
    EXPECT_NEAR(inner / energy, 0.25, 0.02);
    EXPECT_NEAR(d2 / energy, r * r / 2.0 + 1.0 / 3, 0.02 * r * r / 2.0);
    // A pixel is lit when a sample falls within its bilinear footprint, a 2 x 2 square: 4 / (2 pi s)
    // samples on average. Samples placed at random would leave a fraction exp(-that) dark; the golden
    // angle spreads them more evenly than chance.
    EXPECT_GT(static_cast<double>(inside_lit) / inside_px, 1.0 - std::exp(-4.0 / (2 * std::numbers::pi * spacing)));
  }
}

TEST(Spiral, RadiusZeroIsExactlyTheIdentity) {
  Frame f = black_frame(40, 30, 10.0f, 0.0f);
  f.color = random_image(40, 30, 3, 0.0f, 5.0f, 3);
  for (const double spacing : {0.5, 1.0, 8.0}) {
    const Image out = cpu_spiral(f, spiral_options(21, 2, spacing));
    EXPECT_EQ(out.pixels, f.color.pixels) << spacing;
  }
}

// At a constant CoC every pixel blends the same samples with the same weights: a convolution whose
// weights sum to one (a constant image stays constant), so light is conserved away from the borders.
TEST(Spiral, ConstantCocConservesEnergyAwayFromTheBorders) {
  const int w = 80, h = 64, margin = 20;
  Frame f = black_frame(w, h, 10.0f, 7.3f);
  f.color = random_image_in_black_border(w, h, margin, 11);
  for (const double spacing : {0.5, 1.0, 4.0}) {
    const Image out = cpu_spiral(f, spiral_options(17, 1, spacing));  // largest radius 8
    EXPECT_NEAR(rgb_sum(out) / rgb_sum(f.color), 1.0, 1e-5) << spacing;
  }
}

// Where samples stop contributing the blend keeps the running average, which weights the sample found
// after i others by 1 / (i + 2) instead of 1 / (samples + 1): a blurred foreground light over a sharp,
// dark background is brightest next to the light and fades outwards (a uniform disc would be flat),
// and its total exceeds the light's own (the blog's "the current average is allowed to grow stronger").
// For contrast, the same light at a constant CoC (above) is conserved.
TEST(Spiral, BlurredForegroundOverSharpBackgroundIsNotConserved) {
  const int w = 128, h = 128, cx = 64, cy = 64;
  const float r = 16.0f, light = 100.0f;
  Frame f = black_frame(w, h, kFocusM, 0.0f);  // in focus, CoC 0
  for (int c = 0; c < 3; ++c) f.color.px(cx, cy)[c] = light;
  *f.depth_m.px(cx, cy) = 1.0f;  // in front of the focus plane
  *f.radius_px.px(cx, cy) = r;
  const Image out = cpu_spiral(f, spiral_options(41, 1, 0.5));
  double energy = 0, near_ring = 0, far_ring = 0;
  int near_n = 0, far_n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double v = out.px(x, y)[0], d = std::hypot(x - cx, y - cy);
      energy += v;
      if (d >= 2 && d < 4) near_ring += v, ++near_n;
      if (d >= 8 && d < 10) far_ring += v, ++far_n;
    }
  near_ring /= near_n, far_ring /= far_n;
  std::printf("[spiral] foreground light over a sharp background: energy %.3f x the light's; mean at 2-4 px %.4f, "
              "at 8-10 px %.4f\n",
              energy / light, near_ring, far_ring);
  EXPECT_GT(energy / light, 1.1);
  EXPECT_GT(near_ring, 2.0 * far_ring);
  EXPECT_GT(far_ring, 0.0);
}

// The background clamp: a sample behind the pixel reaches it only up to clamp_factor x the pixel's own
// CoC. A sharp (CoC 0) pixel next to a blurred background light stays exactly as it is.
TEST(Spiral, BackgroundDoesNotBlurOverASharpPixel) {
  const int w = 64, h = 64;
  Frame f = black_frame(w, h, 10.0f, 12.0f);  // a blurred background...
  for (int c = 0; c < 3; ++c) f.color.px(32, 32)[c] = 100.0f;
  for (int y = 28; y <= 36; ++y)  // ...and a sharp foreground patch beside the light
    for (int x = 38; x <= 46; ++x) *f.depth_m.px(x, y) = kFocusM, *f.radius_px.px(x, y) = 0.0f;
  const Image out = cpu_spiral(f, spiral_options(25, 1, 0.5));
  for (int y = 28; y <= 36; ++y)
    for (int x = 38; x <= 46; ++x) EXPECT_EQ(out.px(x, y)[0], 0.0f) << x << "," << y;
  // The blurred background around the patch does receive the light.
  EXPECT_GT(out.px(36, 32)[0], 0.0f);
}

// The GPU runs the CPU's table and operations: on a point light through the whole pipeline (lens,
// CoC pass on each side) it agrees within the method's stated bound.
TEST(Spiral, GpuPointLightMatchesTheCpuReference) {
  const int w = 96, h = 72;
  Image color(w, h, 3), depth(w, h, 1, 10.0f);
  for (int c = 0; c < 3; ++c) color.px(40, 30)[c] = 100.0f;
  *depth.px(60, 40) = 1.0f;  // one near pixel, so near and far both occur
  const FilterOptions o = spiral_options(21, 1, 0.5);
  const Lens lens = with_max_coc_radius(Lens{}, depth, 12.0);
  const Image cpu = run_cpu(find_method("spiral"), color, depth, lens, o, 2);
  const Image gpu = run_gpu(context(), find_method("spiral"), color, depth, lens, o);
  const double error = max_abs_diff(gpu, cpu) / 100.0;
  std::printf("[spiral] GPU vs CPU on a point light: %.3g of the light (bound %.3g)\n", error,
              find_method("spiral").gpu_tolerance(o));
  EXPECT_LE(error, find_method("spiral").gpu_tolerance(o));
}

}  // namespace
}  // namespace bokeh
