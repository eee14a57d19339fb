#include <gtest/gtest.h>

#include <cmath>

#include "stats.hpp"

namespace bokeh {
namespace {

TEST(PowerLawFit, RecoversExponentAndCoefficient) {
  std::vector<double> n = {5, 9, 13, 21, 41}, t;
  for (double x : n) t.push_back(0.25 * std::pow(x, 1.7));
  const PowerLawFit fit = fit_power_law(n, t);
  EXPECT_NEAR(fit.exponent, 1.7, 1e-12);
  EXPECT_NEAR(fit.coefficient, 0.25, 1e-12);
  EXPECT_NEAR(fit.r_squared, 1.0, 1e-12);
}

TEST(PowerLawFit, RejectsDegenerateInput) {
  EXPECT_THROW(fit_power_law({5}, {1}), std::invalid_argument);
  EXPECT_THROW(fit_power_law({5, 5}, {1, 2}), std::invalid_argument);
  EXPECT_THROW(fit_power_law({5, 9}, {0, 2}), std::invalid_argument);
}

}  // namespace
}  // namespace bokeh
