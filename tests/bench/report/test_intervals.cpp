// The distribution-free interval of a median over rounds, against closed forms and a known
// distribution.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "intervals.hpp"
#include "stats.hpp"

namespace bokeh {
namespace {

// The order statistics it picks, from the binomial tail by hand: n = 10 -> x(2), x(9) (P(B <= 1) =
// 11 / 1024 <= 2.5% < P(B <= 2) = 56 / 1024); n = 15 -> x(4), x(12) (P(B <= 3) = 576 / 32768);
// n < 6 -> min and max (P(B = 0) = 2^-n > 2.5%).
TEST(Intervals, TheMedianIntervalIsTheBinomialOrderStatistics) {
  auto interval_of = [](int n) {
    std::vector<double> v(static_cast<std::size_t>(n));
    std::iota(v.rbegin(), v.rend(), 1.0);  // n .. 1: sorted inside
    return median_interval(v);
  };
  const Interval ten = interval_of(10), fifteen = interval_of(15), five = interval_of(5), one = interval_of(1);
  EXPECT_EQ(ten.estimate, 5.5);
  EXPECT_EQ(ten.low, 2.0);
  EXPECT_EQ(ten.high, 9.0);
  EXPECT_EQ(fifteen.low, 4.0);
  EXPECT_EQ(fifteen.high, 12.0);
  EXPECT_EQ(five.low, 1.0);
  EXPECT_EQ(five.high, 5.0);
  EXPECT_EQ(one.low, 1.0);
  EXPECT_EQ(one.high, 1.0);
  // Non-finite values are left out; none left is NaN, not a crash.
  EXPECT_EQ(median_interval({1.0, std::nan(""), 3.0}).estimate, 2.0);
  EXPECT_TRUE(std::isnan(median_interval(std::vector<double>{}).estimate));
  EXPECT_EQ(median_interval(RoundValues{{0, 2.5}, {3, 2.5}, {9, 2.5}}).relative_half_width(), 0.0);
}

// Drift that moves a whole round (the machine slowing by up to 3x) cancels in a ratio taken within
// each round and in an exponent fitted to each round's own curve: both intervals stay exact. Taken
// apart, a median's interval is wide.
TEST(Intervals, DriftCommonToARoundCancelsInPairedRatiosAndExponents) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> drift(1.0, 3.0);
  const std::vector<double> n = {9, 17, 33, 65};
  RoundValues naive, flag;
  std::vector<double> exponents;
  for (int r = 0; r < 12; ++r) {
    const double d = drift(rng);
    naive[r] = 12.0 * d;
    flag[r] = 4.0 * d;
    std::vector<double> t;
    for (double x : n) t.push_back(0.01 * std::pow(x, 1.5) * d);
    exponents.push_back(fit_power_law(n, t).exponent);
  }
  const Interval ratio = *paired_ratio_interval(naive, flag);
  EXPECT_DOUBLE_EQ(ratio.estimate, 3.0);
  EXPECT_NEAR(ratio.low, 3.0, 1e-12);
  EXPECT_NEAR(ratio.high, 3.0, 1e-12);
  const Interval exponent = median_interval(exponents);
  EXPECT_NEAR(exponent.low, 1.5, 1e-9);
  EXPECT_NEAR(exponent.high, 1.5, 1e-9);
  EXPECT_GT(median_interval(naive).relative_half_width(), 0.1);
  EXPECT_FALSE(paired_ratio_interval(naive, RoundValues{{40, 1.0}}).has_value()) << "no shared round";
}

// Coverage: for samples of a known distribution (lognormal, median 1), the 95% interval of the
// median covers 1 in at least 95% of datasets (exactly 1 - 2 P(B <= 3) = 96.5% at 15 rounds, and
// 97.9% at 10); 2000 datasets put the binomial standard error near 0.4%.
TEST(Intervals, TheMedianIntervalCoversTheTrueMedianAsOftenAsStated) {
  std::mt19937_64 rng(11);
  std::lognormal_distribution<double> sample(0.0, 0.2);
  for (const auto& [rounds, exact] : {std::pair{15, 0.9648}, std::pair{10, 0.9785}}) {
    int covered = 0;
    const int datasets = 2000;
    for (int k = 0; k < datasets; ++k) {
      std::vector<double> v;
      for (int r = 0; r < rounds; ++r) v.push_back(sample(rng));
      covered += median_interval(v).covers(1.0);
    }
    EXPECT_NEAR(static_cast<double>(covered) / datasets, exact, 0.015) << rounds << " rounds";
  }
}

// Two runs of the same machine (two datasets of one lognormal distribution): run A's 95% interval
// of the median covers run B's estimate less often than 95% (83% for a normal interval:
// P(|Z| < 1.96 / sqrt(2))), while A's repeat-run interval covers it at least about 95% of the time.
TEST(Intervals, TheRepeatRunIntervalCoversASecondRunsEstimateAboutAsOftenAsStated) {
  std::mt19937_64 rng(13);
  std::lognormal_distribution<double> sample(0.0, 0.2);
  auto dataset = [&] {
    std::vector<double> v;
    for (int r = 0; r < 15; ++r) v.push_back(sample(rng));
    return v;
  };
  int confidence_covers = 0, repeat_covers = 0;
  const int pairs = 2000;
  for (int k = 0; k < pairs; ++k) {
    const Interval a = median_interval(dataset());
    const double estimate_b = median_interval(dataset()).estimate;
    confidence_covers += a.covers(estimate_b);
    repeat_covers += repeat_run(a).covers(estimate_b);
  }
  EXPECT_LT(static_cast<double>(confidence_covers) / pairs, 0.93);
  EXPECT_GT(static_cast<double>(repeat_covers) / pairs, 0.93);
  const Interval i = repeat_run({2.0, 1.9, 2.2});
  EXPECT_DOUBLE_EQ(i.estimate, 2.0);
  EXPECT_NEAR(i.low, 2.0 - 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(i.high, 2.0 + 0.2 * std::sqrt(2.0), 1e-12);
}

// Student's t 97.5% quantile against its closed forms (1 degree of freedom: Cauchy, tan(0.475 pi); 2:
// 0.95 sqrt(2 / (1 - 0.95^2))), a published table (9: 2.262157) and the normal limit;
// a repeat-run interval takes t (for the spread's degrees of freedom) times the earlier runs' spread where
// that is wider than its own side.
TEST(Intervals, StudentTQuantileAndTheRunToRunSpread) {
  EXPECT_NEAR(student_t_975(1), std::tan(0.475 * std::acos(-1.0)), 1e-5);
  EXPECT_NEAR(student_t_975(2), 0.95 * std::sqrt(2 / (1 - 0.95 * 0.95)), 1e-5);  // F(t) = 1/2 + t / (2 sqrt(t^2 + 2))
  EXPECT_NEAR(student_t_975(9), 2.262157, 1e-5);
  EXPECT_NEAR(student_t_975(2000), 1.959964, 2e-3);
  EXPECT_THROW(student_t_975(0), std::invalid_argument);
  const Interval i = repeat_run({2.0, 1.9, 2.2}, 0.05, 2);  // 3 runs: t(2) * 0.05 = 0.215, wider than both sides
  EXPECT_NEAR(i.low, 2.0 - std::sqrt(2.0) * student_t_975(2) * 0.05, 1e-12);
  EXPECT_NEAR(i.high, 2.0 + std::sqrt(2.0) * student_t_975(2) * 0.05, 1e-12);
  const Interval own = repeat_run({2.0, 1.9, 2.2}, 0.05, 0);  // one earlier run has no spread
  EXPECT_NEAR(own.low, 2.0 - 0.1 * std::sqrt(2.0), 1e-12);
}

}  // namespace
}  // namespace bokeh
