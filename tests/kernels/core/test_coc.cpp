// Circle of confusion: equation (1) against values worked out by hand, and the units.
#include <gtest/gtest.h>

#include <cmath>

#include "coc.hpp"
#include "lens.hpp"

namespace bokeh {
namespace {

// 50 mm f/2 (A = 25 mm), focus 3 m, 36 mm sensor, 800 px wide. Equation (1) gives the diameter on the
// sensor: c = A f |D - P| / (D (P - f)) = 25 * 50 * |D - 3000| / (D * 2950) mm; the radius in px is
// c / 2 * 800 / 36.
Lens test_lens() { return Lens{50.0, 2.0, 36.0, 3.0, CocModel::thin_lens}; }

TEST(Coc, ClosedFormValues) {
  const Lens lens = test_lens();
  struct Case { double depth_m, radius_px; };
  const double per_ratio = 25.0 * 50.0 / 2950.0 / 2.0 * 800.0 / 36.0;  // 4.7081 px per unit |D-P|/D
  const Case cases[] = {{3.0, 0.0}, {1.5, per_ratio * 1.0}, {6.0, per_ratio * 0.5}, {1.0, per_ratio * 2.0},
                        {1e6, per_ratio * (1e6 - 3.0) / 1e6}};
  for (const Case& c : cases) EXPECT_NEAR(coc_radius_px(lens, c.depth_m, 800), c.radius_px, 1e-9) << c.depth_m;
  EXPECT_NEAR(per_ratio, 4.708097928, 1e-8);  // the number itself, computed by hand
}

TEST(Coc, FocusDistanceGivesRadiusZeroInThePass) {
  Image depth(4, 1, 1, 3.0f);
  const Image r = coc_radius_image(depth, test_lens(), 40.0f);
  for (float v : r.pixels) EXPECT_EQ(v, 0.0f);
}

TEST(Coc, FocalPlaneAtFocalLengthModelUsesPInsteadOfPMinusF) {
  Lens lens = test_lens();
  const double thin = coc_radius_px(lens, 1.5, 800);
  lens.model = CocModel::focal_plane_at_f;
  EXPECT_NEAR(coc_radius_px(lens, 1.5, 800) / thin, 2950.0 / 3000.0, 1e-12);
}

TEST(Coc, ClampsToMaxRadiusAndNearZeroDepthStaysFinite) {
  Image depth(800, 1, 1, 3.0f);  // 800 px wide, as test_lens's numbers assume
  depth.pixels[0] = 1e-6f, depth.pixels[1] = 0.01f, depth.pixels[2] = 2.9f;
  const Image r = coc_radius_image(depth, test_lens(), 40.0f);
  EXPECT_EQ(r.pixels[0], 40.0f);
  EXPECT_EQ(r.pixels[1], 40.0f);
  EXPECT_NEAR(r.pixels[2], 4.708097928 * 0.1 / 2.9, 1e-5);
}

TEST(Coc, BadDepthIsANamedError) {
  Image depth(2, 2, 1, 1.0f);
  *depth.px(1, 1) = -1.0f;
  try {
    coc_radius_image(depth, test_lens(), 40.0f);
    FAIL() << "negative depth accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("(1, 1)"), std::string::npos) << e.what();
  }
  *depth.px(1, 1) = std::nanf("");
  EXPECT_THROW(coc_radius_image(depth, test_lens(), 40.0f), std::invalid_argument);
}

TEST(Coc, DegenerateLensesAreRejectedOrPinhole) {
  Lens lens = test_lens();
  lens.focus_distance_m = 0.04;  // nearer than the focal length: nothing can be focused
  EXPECT_THROW(validate(lens), std::invalid_argument);
  lens = test_lens();
  lens.f_stop = 0;
  EXPECT_THROW(validate(lens), std::invalid_argument);
  lens = test_lens();
  lens.f_stop = 1e12;  // a pinhole: everything sharp
  EXPECT_LT(coc_radius_px(lens, 0.5, 800), 1e-9);
}

TEST(Coc, FittingTheApertureReachesTheRequestedMaxRadius) {
  Image depth(3, 1, 1);
  depth.pixels = {1.0f, 3.0f, 50.0f};
  const Lens fitted = with_max_coc_radius(test_lens(), depth, 40.0);
  EXPECT_NEAR(coc_radius_px(fitted, 1.0, 3), 40.0, 1e-9);
}

}  // namespace
}  // namespace bokeh
