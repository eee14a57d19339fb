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

TEST(ParetoFront, KeepsOnlyPointsNothingBeatsOnBoth) {
  //                 0    1    2    3    4     5
  const std::vector<double> cost = {5, 1, 2, 3, 10, 2};
  const std::vector<double> quality = {40, 20, 18, 30, 45, 25};
  // 1 (cheapest), 5 (better than 1 at cost 2; 2 is dominated by it), 3, 0, 4.
  EXPECT_EQ(pareto_front(cost, quality), (std::vector<std::size_t>{1, 5, 3, 0, 4}));
  // With a 6-unit tolerance, 5 (+5) and 4 (+5) are not measurably better than what precedes them.
  EXPECT_EQ(pareto_front(cost, quality, 6.0), (std::vector<std::size_t>{1, 3, 0}));
}

TEST(ParetoFront, InfiniteQualityIsTheTop) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(pareto_front({3, 1, 2}, {inf, 10, inf}), (std::vector<std::size_t>{1, 2}));
}

}  // namespace
}  // namespace bokeh
