// Apertures (issue 23): the exact reference's coverage of any aperture against closed forms (a regular
// n-gon of circumradius R has area n R^2 sin(2 pi / n) / 2, the disc pi R^2), against numerical
// integration of the shape's indicator, and against conservation of energy; the aperture's names,
// lens files and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "aperture.hpp"
#include "exact_scatter.hpp"
#include "lens.hpp"
#include "test_support.hpp"

namespace bokeh {
namespace {

using namespace bokeh::test;
constexpr double kPi = std::numbers::pi;

double sum_channel(const std::vector<double>& rgb, int k) {
  double s = 0.0;
  for (std::size_t i = k; i < rgb.size(); i += 3) s += rgb[i];
  return s;
}

// The exact scatter of a unit point at the centre of a kSize x kSize image.
constexpr int kSize = 31, kC = kSize / 2;
std::vector<double> point_spread(const Aperture& a, float radius_px) {
  Image color(kSize, kSize, 3);
  color.px(kC, kC)[0] = 1.0f;
  return exact_scatter_double(color, Image(kSize, kSize, 1, radius_px), Image(), ScatterComposite::energy_sum, 2, a);
}
double share(const std::vector<double>& out, int x, int y) { return out[(static_cast<std::size_t>(y) * kSize + x) * 3]; }

// Midpoint integration of the shape's indicator (gauge <= R) over the square at offset (dx, dy):
// independent of the clipping; the error is about the edge length in the square over kSteps.
double integrated_coverage(const Aperture& a, double r, int dx, int dy) {
  constexpr int kSteps = 200;
  int inside = 0;
  for (int j = 0; j < kSteps; ++j)
    for (int i = 0; i < kSteps; ++i)
      inside += a.gauge(dx - 0.5 + (i + 0.5) / kSteps, dy - 0.5 + (j + 0.5) / kSteps) <= r;
  return static_cast<double>(inside) / (kSteps * kSteps);
}

TEST(Aperture, EachPolygonsExactAreaIsItsClosedForm) {
  for (int n = 5; n <= 9; ++n)
    for (double rotation : {0.0, 17.0, 90.0})
      for (float r : {1.5f, 4.75f, 10.0f, 13.2f}) {
        SCOPED_TRACE(::testing::Message() << n << " blades, rotation " << rotation << ", radius " << r);
        const Aperture a{n, rotation, 0.0};
        const std::vector<double> out = point_spread(a, r);
        EXPECT_NEAR(sum_channel(out, 0), 1.0, 1e-12);  // every source's light is spread, none lost
        // The centre square lies wholly inside (coverage exactly 1): its share is 1 / the shape's area.
        const double closed_form = n * static_cast<double>(r) * r * std::sin(2 * kPi / n) / 2;
        EXPECT_DOUBLE_EQ(a.area(r), closed_form);
        EXPECT_NEAR(1.0 / share(out, kC, kC), closed_form, 1e-12 * closed_form);
      }
}

TEST(Aperture, CurvedBladesRunFromThePolygonToTheDisc) {
  constexpr float kR = 9.5f;
  const double disc = kPi * kR * kR, hexagon = Aperture{6, 0, 0}.area(kR);
  // Curvature 1: the enlarged hexagon holds the disc, so the shape is the disc: pi R^2 through sectors.
  const std::vector<double> round = point_spread(Aperture{6, 0, 1.0}, kR), disc_spread = point_spread(Aperture{}, kR);
  EXPECT_NEAR(1.0 / share(round, kC, kC), disc, 1e-11 * disc);
  for (std::size_t i = 0; i < round.size(); ++i) ASSERT_NEAR(round[i], disc_spread[i], 1e-14) << i;
  // In between: strictly between the two, and equal to the integrated indicator.
  const Aperture curved{6, 0, 0.5};
  const std::vector<double> out = point_spread(curved, kR);
  const double area = 1.0 / share(out, kC, kC);
  EXPECT_GT(area, hexagon + 1.0);
  EXPECT_LT(area, disc - 1.0);
  for (int dy = -10; dy <= 10; dy += 4)
    for (int dx = -10; dx <= 10; ++dx)
      ASSERT_NEAR(share(out, kC + dx, kC + dy) * area, integrated_coverage(curved, kR, dx, dy), 6e-3) << dx << "," << dy;
}

TEST(Aperture, EachPixelsCoverageMatchesIntegration) {
  constexpr float kR = 6.3f;
  for (const Aperture a : {Aperture{5, 0, 0}, Aperture{7, 33, 0}, Aperture{6, 0, 0}}) {
    SCOPED_TRACE(a.name());
    const std::vector<double> out = point_spread(a, kR);
    const double area = a.area(kR);
    for (int dy = -7; dy <= 7; dy += 2)
      for (int dx = -7; dx <= 7; ++dx)
        ASSERT_NEAR(share(out, kC + dx, kC + dy) * area, integrated_coverage(a, kR, dx, dy), 6e-3) << dx << "," << dy;
  }
}

TEST(Aperture, APentagonAtRotationZeroPointsUpAndIsNotVerticallySymmetric) {
  const Aperture up{5, 0, 0}, side{5, 90, 0}, hexagon{6, 0, 0};
  EXPECT_FALSE(up.vertically_symmetric());
  EXPECT_TRUE(side.vertically_symmetric());
  EXPECT_TRUE(hexagon.vertically_symmetric());
  EXPECT_TRUE(Aperture{}.vertically_symmetric());
  // The vertex reaches R above the centre (y down: negative rows), the flat edge only R cos(36 deg) below.
  constexpr float kR = 10.0f;
  EXPECT_NEAR(up.gauge(0, -kR), kR, 1e-12);
  EXPECT_NEAR(up.gauge(0, kR * std::cos(kPi / 5)), kR, 1e-12);
  const std::vector<double> out = point_spread(up, kR);
  EXPECT_GT(share(out, kC, kC - 9), 0.0);  // 9 px up: inside
  EXPECT_EQ(share(out, kC, kC + 9), 0.0);  // 9 px down: beyond the edge at 8.09
  // The mirror of a vertically symmetric shape's spread is itself; the upward pentagon's is not.
  for (const Aperture& a : {side, hexagon}) {
    const std::vector<double> s = point_spread(a, kR);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) ASSERT_NEAR(share(s, x, y), share(s, x, kSize - 1 - y), 1e-15) << a.name();
  }
}

TEST(Aperture, EnergyIsConservedAndAUniformImageStaysUniform) {
  constexpr int kW = 48, kH = 40, kMargin = 10;
  for (const Aperture a : {Aperture{5, 0, 0}, Aperture{6, 0, 0}, Aperture{9, 10, 0.4}}) {
    SCOPED_TRACE(a.name());
    Image color(kW, kH, 3);
    const Image noise = random_image(kW, kH, 3, 0.0f, 5.0f, 4);
    for (int y = kMargin; y < kH - kMargin; ++y)
      for (int x = kMargin; x < kW - kMargin; ++x)
        for (int k = 0; k < 3; ++k) color.px(x, y)[k] = noise.px(x, y)[k];
    const Image radius = random_image(kW, kH, 1, 0.0f, 9.0f, 5);
    const std::vector<double> out = exact_scatter_double(color, radius, Image(), ScatterComposite::energy_sum, 2, a);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(sum_channel(out, k), channel_sum(color, k), 1e-9 * channel_sum(color, k));
    // One radius everywhere: the interior receives a whole shape's worth of sources, in both modes.
    const Image uniform(kW, kH, 3, 2.0f);
    for (ScatterComposite mode : {ScatterComposite::energy_sum, ScatterComposite::depth_ordered}) {
      const std::vector<double> u =
          exact_scatter_double(uniform, Image(kW, kH, 1, 6.4f), Image(kW, kH, 1, 10.0f), mode, 2, a);
      for (int y = 7; y < kH - 7; ++y)
        for (int x = 7; x < kW - 7; ++x)
          ASSERT_NEAR(u[(static_cast<std::size_t>(y) * kW + x) * 3], 2.0, 1e-9) << to_string(mode) << " " << x << "," << y;
    }
  }
}

TEST(Aperture, TheCacheKeyNamesTheShapeAndKeepsTheDiscs) {
  const Image color(8, 8, 3, 1.0f), radius(8, 8, 1, 2.0f);
  const auto disc = exact_scatter_key(color, radius, Image(), ScatterComposite::energy_sum);
  EXPECT_EQ(exact_scatter_key(color, radius, Image(), ScatterComposite::energy_sum, Aperture{}), disc);
  EXPECT_NE(exact_scatter_key(color, radius, Image(), ScatterComposite::energy_sum, Aperture{6, 0, 0}), disc);
  EXPECT_NE(exact_scatter_key(color, radius, Image(), ScatterComposite::energy_sum, Aperture{6, 0, 0}),
            exact_scatter_key(color, radius, Image(), ScatterComposite::energy_sum, Aperture{6, 30, 0}));
}

TEST(Aperture, NamesRoundTripAndBadOnesAreRefusedByName) {
  for (const std::string name : {"disc", "blades5", "blades6-rot30", "blades7-curv0.5", "blades9-rot-12.5-curv1"})
    EXPECT_EQ(parse_aperture(name).name(), name);
  EXPECT_EQ(parse_aperture("blades5-rot90"), (Aperture{5, 90, 0}));
  auto message = [](const std::string& text) {
    try {
      parse_aperture(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("hexagon").find("'hexagon' is not 'disc' or 'blades<N>"), std::string::npos) << message("hexagon");
  EXPECT_NE(message("blades4").find("blades must be 0 (a disc) or 5..9, got 4"), std::string::npos) << message("blades4");
  EXPECT_NE(message("blades6-curv2").find("curvature must be within [0, 1]"), std::string::npos);
  EXPECT_NE(message("blades6-rot400").find("rotation_deg"), std::string::npos);
}

TEST(Aperture, LensFilesCarryItAndRefuseBadOnes) {
  const auto dir = std::filesystem::temp_directory_path() / "bokeh_test_aperture";
  std::filesystem::create_directories(dir);
  auto lens_with = [&](const std::string& aperture) {
    const auto path = (dir / "lens.json").string();
    std::ofstream(path) << R"({"focal_length_mm": 50, "f_stop": 2, "sensor_width_mm": 36, "focus_distance_m": 3,
                               "aperture": )" << aperture << "}";
    return load_lens_json(path);
  };
  EXPECT_EQ(lens_with(R"("blades6")").aperture, (Aperture{6, 0, 0}));
  EXPECT_EQ(lens_with(R"({"blades": 5, "rotation_deg": 90})").aperture, (Aperture{5, 90, 0}));
  EXPECT_EQ(lens_with(R"({"blades": 0})").aperture, Aperture{});
  for (const auto& [bad, says] : std::vector<std::pair<std::string, std::string>>{
           {R"({"blades": 4})", "blades must be 0 (a disc) or 5..9"},
           {R"({"blades": 6, "angle": 3})", "unknown field 'angle'"},
           {R"({"rotation_deg": 3})", "lacks 'blades'"},
           {R"(6)", "must be a name"},
           {R"("square")", "'square' is not 'disc'"}}) {
    try {
      lens_with(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("'aperture'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace bokeh
