// The naive gather for any aperture (issue 23) against independent truth: the lattice offsets a light's
// shape covers, counted in double precision from the aperture's polygon, and the light it conserves.
#include <gtest/gtest.h>

#include <cmath>

#include "aperture.hpp"
#include "naive_shape.hpp"

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

}  // namespace
}  // namespace bokeh
