// Error metrics against values worked out by hand on tiny images, and the display helpers' layout.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "image_io.hpp"
#include "metrics.hpp"

namespace bokeh {
namespace {

Image gray(int w, int h, float v) { return Image(w, h, 3, v); }

TEST(Metrics, TwoByTwoMatchesHandComputedValues) {
  // Reference: every value 0.5 except one 1.0 (the peak). Result: one value +0.3, another -0.1.
  Image reference = gray(2, 2, 0.5f);
  reference.px(1, 1)[2] = 1.0f;
  Image result = reference;
  result.px(0, 0)[0] += 0.3f;
  result.px(1, 0)[1] -= 0.1f;
  const double d0 = static_cast<double>(result.px(0, 0)[0]) - 0.5, d1 = static_cast<double>(result.px(1, 0)[1]) - 0.5;
  const ErrorMetrics m = compare_images(result, reference);
  const double rmse = std::sqrt((d0 * d0 + d1 * d1) / 12.0);  // ~ sqrt(0.1 / 12)
  EXPECT_NEAR(m.rmse, std::sqrt(0.1 / 12.0), 1e-7);
  EXPECT_NEAR(m.rmse, rmse, 1e-15);
  EXPECT_NEAR(m.psnr_db, 20.0 * std::log10(1.0 / rmse), 1e-12);  // peak = 1.0
  EXPECT_NEAR(m.psnr_db, 20.8, 0.01);                            // 10 log10(120)
  EXPECT_NEAR(m.max_abs_error, 0.3, 1e-7);
  EXPECT_NEAR(m.mean_relative_energy_error, 0.2 / 6.5, 1e-7);  // sums 6.7 vs 6.5
  EXPECT_LT(m.ssim, 1.0);
  EXPECT_GT(m.ssim, 0.0);
}

TEST(Metrics, PsnrPeakIsTheReferenceMaximum) {
  const Image reference = gray(3, 2, 4.0f);  // HDR: peak 4
  const Image result = gray(3, 2, 3.0f);
  const ErrorMetrics m = compare_images(result, reference);
  EXPECT_DOUBLE_EQ(m.rmse, 1.0);
  EXPECT_NEAR(m.psnr_db, 20.0 * std::log10(4.0), 1e-12);
  EXPECT_DOUBLE_EQ(m.mean_relative_energy_error, 0.25);
  // A black reference has no peak: 1 stands in, and relative energy error is infinite.
  const ErrorMetrics black = compare_images(gray(3, 2, 0.5f), gray(3, 2, 0.0f));
  EXPECT_NEAR(black.psnr_db, 20.0 * std::log10(1.0 / 0.5), 1e-12);
  EXPECT_EQ(black.mean_relative_energy_error, std::numeric_limits<double>::infinity());
}

// The interior leaves margin_px out on every side: an error there counts in the whole-image metrics
// only, one inside counts in both, and a margin that leaves nothing gives NaN (null in JSON), not "exact".
TEST(Metrics, InteriorLeavesTheMarginOut) {
  const Image reference = gray(8, 6, 2.0f);
  Image border_error = reference;
  border_error.px(1, 4)[0] = 3.0f;  // 1 px from the bottom and 1 px from the left
  EXPECT_GT(compare_images(border_error, reference).rmse, 0.0);
  const ErrorMetrics inside_clean = compare_interior(border_error, reference, 2);
  EXPECT_EQ(inside_clean.rmse, 0.0);
  EXPECT_EQ(inside_clean.psnr_db, std::numeric_limits<double>::infinity());
  Image inner_error = reference;
  inner_error.px(2, 3)[1] = 3.0f;  // inside the 4x2 interior of 24 values
  const ErrorMetrics inside = compare_interior(inner_error, reference, 2);
  EXPECT_DOUBLE_EQ(inside.rmse, std::sqrt(1.0 / 24.0));
  EXPECT_DOUBLE_EQ(inside.max_abs_error, 1.0);
  EXPECT_EQ(compare_interior(inner_error, reference, 0).rmse, compare_images(inner_error, reference).rmse);
  EXPECT_TRUE(std::isnan(compare_interior(inner_error, reference, 3).rmse));  // 6 - 2 x 3 rows: none left
}

TEST(Metrics, IdenticalImagesGiveInfinitePsnrAndSsimOneWithoutNaN) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 20.0f);
  Image image(24, 17, 3);
  for (float& v : image.pixels) v = u(rng);
  for (const Image& img : {image, gray(24, 17, 0.0f), gray(2, 2, 0.7f), gray(1, 1, 0.0f)}) {
    const ErrorMetrics m = compare_images(img, img);
    EXPECT_EQ(m.rmse, 0.0);
    EXPECT_EQ(m.psnr_db, std::numeric_limits<double>::infinity());
    EXPECT_EQ(m.max_abs_error, 0.0);
    EXPECT_EQ(m.mean_relative_energy_error, 0.0);
    EXPECT_NEAR(m.ssim, 1.0, 1e-12);
    EXPECT_FALSE(std::isnan(m.ssim));
  }
}

TEST(Metrics, SsimOfFlatImagesIsTheLuminanceTerm) {
  // With no variance anywhere SSIM = (2 a b + C1) / (a^2 + b^2 + C1) on tone-mapped luminance; gray v
  // tone-maps to v / (1 + v): 1 -> 0.5, 3 -> 0.75. Holds for the 11x11 window and the 1x1 one (2x2 image).
  const double a = 0.75, b = 0.5, c1 = 1e-4;
  const double expected = (2 * a * b + c1) / (a * a + b * b + c1);
  EXPECT_NEAR(compare_images(gray(20, 16, 3.0f), gray(20, 16, 1.0f)).ssim, expected, 1e-6);
  EXPECT_NEAR(compare_images(gray(2, 2, 3.0f), gray(2, 2, 1.0f)).ssim, expected, 1e-6);
}

TEST(Metrics, SsimDropsWithStructureLossAndIsSymmetric) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  Image noisy(32, 32, 3);
  for (float& v : noisy.pixels) v = u(rng);
  const Image flat = gray(32, 32, 1.0f);
  const double s = compare_images(flat, noisy).ssim;
  EXPECT_LT(s, 0.2);  // no shared structure: only the luminance term survives, times a near-0 contrast term
  EXPECT_NEAR(s, compare_images(noisy, flat).ssim, 1e-12);
}

TEST(Metrics, ShapeMismatchThrows) {
  EXPECT_THROW(compare_images(gray(2, 2, 0.0f), gray(2, 3, 0.0f)), std::invalid_argument);
  EXPECT_THROW(compare_images(Image(2, 2, 4), gray(2, 2, 0.0f)), std::invalid_argument);
  EXPECT_THROW(compare_images(Image(2, 2, 1), Image(2, 2, 1)), std::invalid_argument);
  EXPECT_THROW(error_heat_map(gray(3, 2, 0.0f), gray(2, 3, 0.0f)), std::invalid_argument);
}

TEST(Metrics, HeatMapRampsFromNoErrorToThePercentileScale) {
  Image reference = gray(10, 10, 0.5f), result = reference;
  result.px(3, 4)[1] += 1.0f;  // one pixel with a large error; the 99th percentile of 100 values is 0
  const Image map = error_heat_map(result, reference);
  ASSERT_EQ(map.channels, 3);
  for (float v : map.pixels) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
  // No error: viridis' dark purple #440154. The scale falls back to the maximum: yellow #fde725.
  EXPECT_NEAR(map.px(0, 0)[0], 0x44 / 255.0, 1e-6);
  EXPECT_NEAR(map.px(0, 0)[2], 0x54 / 255.0, 1e-6);
  EXPECT_NEAR(map.px(3, 4)[0], 0xfd / 255.0, 1e-6);
  EXPECT_NEAR(map.px(3, 4)[1], 0xe7 / 255.0, 1e-6);
}

TEST(Metrics, DisplaySrgbMatchesTheToneMapThenTransferFunction) {
  const Image display = to_display_srgb(gray(1, 1, 1.0f));  // Reinhard: 1 -> 0.5; sRGB(0.5) = 0.7354
  EXPECT_NEAR(display.pixels[0], 1.055 * std::pow(0.5, 1.0 / 2.4) - 0.055, 1e-6);
}

TEST(Metrics, ContactSheetPlacesPanelsSideBySide) {
  Image a = gray(4, 3, 0.25f), b(5, 6, 1, 0.75f);
  const Image sheet = contact_sheet({{"", a}, {"", b}});
  EXPECT_EQ(sheet.width, 8 + 4 + 8 + 5 + 8);
  EXPECT_EQ(sheet.height, 8 + 6 + 8);
  EXPECT_FLOAT_EQ(sheet.px(8, 8)[1], 0.25f);
  EXPECT_FLOAT_EQ(sheet.px(11, 10)[2], 0.25f);
  EXPECT_FLOAT_EQ(sheet.px(12, 8)[0], sheet.px(0, 0)[0]);  // gap
  EXPECT_FLOAT_EQ(sheet.px(20, 13)[0], 0.75f);              // single channel shown as gray
  EXPECT_FLOAT_EQ(sheet.px(24, 13)[2], 0.75f);
  EXPECT_THROW(contact_sheet({}), std::invalid_argument);
}

// .ci/setup installs fonts-dejavu-core, so the labels a person reads must be drawn (by OpenImageIO; the
// lean image back-end has no text renderer and leaves the strip blank, as the README says).
TEST(Metrics, ContactSheetDrawsLabels) {
  const Image sheet = contact_sheet({{"reference", gray(80, 10, 0.0f)}});
  EXPECT_EQ(sheet.height, 8 + 20 + 10 + 8);
  if (image_io_backend().name == "lean") {
    Image probe = gray(80, 20, 0.0f);
    EXPECT_FALSE(draw_text(probe, 0, 14, "reference", 14, {1.0f, 1.0f, 1.0f}));
    for (float v : sheet.pixels) ASSERT_LT(v, 0.5f) << "the lean back-end draws no text";
    GTEST_SKIP() << "BOKEH_IMAGE_IO=lean draws no labels (" << image_io_backend().libraries << ")";
  }
  Image probe = gray(80, 20, 0.0f);
  ASSERT_TRUE(draw_text(probe, 0, 14, "reference", 14, {1.0f, 1.0f, 1.0f}))
      << "no DejaVuSans font: install fonts-dejavu-core (as .ci/setup does), or the contact sheets lose their labels";
  float brightest = 0.0f;
  for (int y = 0; y < 28; ++y)
    for (int x = 0; x < sheet.width; ++x) brightest = std::max(brightest, sheet.px(x, y)[0]);
  EXPECT_GT(brightest, 0.5f);
}

TEST(Metrics, DisplayImageWritesValuesWithoutToneMapping) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("bokeh-display-" + std::to_string(std::random_device{}()) + ".png");
  Image image(3, 2, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i) / 17.0f;
  write_display_image(image, path.string());
  const Image back = read_image(path.string(), 3);
  std::filesystem::remove(path);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) EXPECT_NEAR(back.pixels[i], image.pixels[i], 0.5 / 255.0 + 1e-6);
}

}  // namespace
}  // namespace bokeh
