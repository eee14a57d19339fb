// E-divisive means against closed-form truth: synthetic series with steps at known positions.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "changepoints.hpp"

namespace bokeh::history {
namespace {

// Q(tau) straight from Matteson & James's definition (every pair summed afresh): the O(n^2)
// incremental form must give the same numbers.
double q_by_definition(const std::vector<double>& x, std::size_t tau) {
  const std::size_t n = x.size();
  const double m = static_cast<double>(tau), k = static_cast<double>(n - tau);
  double between = 0, left = 0, right = 0;
  for (std::size_t i = 0; i < tau; ++i)
    for (std::size_t j = tau; j < n; ++j) between += std::abs(x[i] - x[j]);
  for (std::size_t i = 0; i < tau; ++i)
    for (std::size_t j = i + 1; j < tau; ++j) left += std::abs(x[i] - x[j]);
  for (std::size_t i = tau; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) right += std::abs(x[i] - x[j]);
  const double e = 2 * between / (m * k) - left / (m * (m - 1) / 2) - right / (k * (k - 1) / 2);
  return m * k / (m + k) * e;
}

// Lognormal noise of relative spread `sd` around `level`, with the given steps (index, factor).
std::vector<double> noisy(std::size_t n, double sd, const std::vector<std::pair<std::size_t, double>>& steps,
                          unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, sd);
  std::vector<double> v;
  for (std::size_t i = 0; i < n; ++i) {
    double level = 10;
    for (const auto& [at, factor] : steps)
      if (i >= at) level *= factor;
    v.push_back(level * std::exp(noise(rng)));
  }
  return v;
}

TEST(EDivisive, IncrementalStatisticEqualsTheDefinition) {
  const std::vector<double> x = noisy(17, 0.3, {{6, 1.5}}, 3);
  const std::vector<double> q = energy_statistics(x, 2);
  for (std::size_t tau = 0; tau < x.size(); ++tau) {
    if (tau < 2 || x.size() - tau < 2) {
      EXPECT_EQ(q[tau], 0.0) << tau;
    } else {
      EXPECT_NEAR(q[tau], q_by_definition(x, tau), 1e-9) << tau;
    }
  }
}

TEST(EDivisive, NoiselessStepIsFoundExactlyWithItsRatio) {
  std::vector<double> v(30, 2.0);
  for (std::size_t i = 12; i < v.size(); ++i) v[i] = 2.2;
  const auto found = e_divisive(v);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].index, 12u);
  EXPECT_NEAR(found[0].ratio, 1.1, 1e-12);
  EXPECT_LE(found[0].p_value, 0.01);
}

TEST(EDivisive, TwoNoisyStepsAtTheirCommits) {
  // +5% and +10% steps in 1% noise: each step is 5-10 noise sds, found at its index with its size; a
  // further (false) change point at p <= 0.01 is rare.
  int found_5 = 0, found_10 = 0, others = 0;
  for (unsigned seed = 1; seed <= 10; ++seed)
    for (const auto& c : e_divisive(noisy(30, 0.01, {{10, 1.05}, {20, 1.10}}, seed), {0.01, 999, 3, seed})) {
      if (c.index == 10) {
        ++found_5;
        EXPECT_NEAR(c.ratio, 1.05, 0.02) << "seed " << seed;
      } else if (c.index == 20) {
        ++found_10;
        EXPECT_NEAR(c.ratio, 1.10, 0.02) << "seed " << seed;
      } else {
        ++others;
      }
    }
  EXPECT_GE(found_5, 9);
  EXPECT_EQ(found_10, 10);
  EXPECT_LE(others, 2);
}

TEST(EDivisive, AaSeriesRarelyHaveChangePoints) {
  // No step: with p <= 0.01, false change points are about 1 in 100 series (one test each when none
  // is found); 200 seeded series may show a few, never many.
  int false_points = 0;
  for (unsigned seed = 1; seed <= 200; ++seed) false_points += e_divisive(noisy(30, 0.05, {}, seed), {0.01, 199, 3, seed}).size();
  EXPECT_LE(false_points, 8);
}

TEST(EDivisive, ShortAndBadSeries) {
  EXPECT_TRUE(e_divisive({1, 2, 3}).empty());  // too short for two segments of 3
  EXPECT_THROW(e_divisive({1, 0, 3, 4, 5, 6}), std::invalid_argument);
  EXPECT_THROW(e_divisive({1, NAN, 3, 4, 5, 6}), std::invalid_argument);
  EXPECT_THROW(e_divisive({1, 2}, {0.01, 0, 3, 1}), std::invalid_argument);
}

}  // namespace
}  // namespace bokeh::history
