// Intervals from a bootstrap over rounds, against closed forms and a known distribution.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "intervals.hpp"
#include "stats.hpp"

namespace bokeh {
namespace {

std::vector<int> rounds(int n) {
  std::vector<int> r(static_cast<std::size_t>(n));
  std::iota(r.begin(), r.end(), 0);
  return r;
}

TEST(Intervals, MediansOverAMultisetOfRounds) {
  const RoundValues v = {{0, 1.0}, {1, 5.0}, {2, 3.0}};
  EXPECT_DOUBLE_EQ(median_over(v, {0, 1, 2}), 3.0);
  EXPECT_DOUBLE_EQ(median_over(v, {1, 1, 0}), 5.0);  // a round drawn twice counts twice
  EXPECT_DOUBLE_EQ(median_over(v, {0, 2, 7}), 2.0);  // round 7 has no sample
  EXPECT_TRUE(std::isnan(median_over(v, {7})));
}

TEST(Intervals, AConstantStatisticHasNoWidth) {
  const RoundBootstrap b(rounds(9));
  const Interval i = b.interval([](const std::vector<int>&) { return 2.5; });
  EXPECT_EQ(i.estimate, 2.5);
  EXPECT_EQ(i.low, 2.5);
  EXPECT_EQ(i.high, 2.5);
  EXPECT_EQ(i.relative_half_width(), 0.0);
}

// Drift that moves a whole round (the machine slowing by up to 3x) cancels in a ratio taken within
// each round, and in a growth exponent of per-N medians: both intervals stay exact. Taken apart, the
// two medians' intervals are wide.
TEST(Intervals, DriftCommonToARoundCancelsInPairedRatiosAndExponents) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> drift(1.0, 3.0);
  const std::vector<double> n = {9, 17, 33, 65};
  std::vector<RoundValues> curve(n.size());
  RoundValues naive, flag;
  for (int r = 0; r < 12; ++r) {
    const double d = drift(rng);
    naive[r] = 12.0 * d;
    flag[r] = 4.0 * d;
    for (std::size_t i = 0; i < n.size(); ++i) curve[i][r] = 0.01 * std::pow(n[i], 1.5) * d;
  }
  const RoundBootstrap b(rounds(12));
  const Interval ratio = b.interval([&](const std::vector<int>& d) { return paired_ratio(naive, flag, d); });
  EXPECT_DOUBLE_EQ(ratio.estimate, 3.0);
  EXPECT_NEAR(ratio.low, 3.0, 1e-12);
  EXPECT_NEAR(ratio.high, 3.0, 1e-12);
  const Interval exponent = b.interval([&](const std::vector<int>& d) {
    std::vector<double> t;
    for (const auto& c : curve) t.push_back(median_over(c, d));
    return fit_power_law(n, t).exponent;
  });
  EXPECT_NEAR(exponent.low, 1.5, 1e-9);
  EXPECT_NEAR(exponent.high, 1.5, 1e-9);
  const Interval median = b.interval([&](const std::vector<int>& d) { return median_over(naive, d); });
  EXPECT_GT(median.relative_half_width(), 0.1);
}

// Coverage: for samples of a known distribution (lognormal, median 1), the 95% interval of the
// median covers 1 in about 95% of datasets. With 15 rounds a percentile bootstrap of a median runs
// a little narrow; 400 datasets put the binomial standard error near 1.1%.
TEST(Intervals, TheMedianIntervalCoversTheTrueMedianAboutAsOftenAsStated) {
  std::mt19937_64 rng(11);
  std::lognormal_distribution<double> sample(0.0, 0.2);
  int covered = 0;
  const int datasets = 400;
  for (int k = 0; k < datasets; ++k) {
    RoundValues v;
    for (int r = 0; r < 15; ++r) v[r] = sample(rng);
    const RoundBootstrap b(rounds(15), 500, static_cast<std::uint64_t>(k) + 1);
    covered += b.interval([&](const std::vector<int>& d) { return median_over(v, d); }).covers(1.0);
  }
  const double coverage = static_cast<double>(covered) / datasets;
  EXPECT_GT(coverage, 0.88);
  EXPECT_LT(coverage, 0.995);
}

// Two runs of the same machine (two datasets of one lognormal distribution): run A's 95% interval
// of the median covers run B's estimate only about 83% of the time (closed form for calibrated
// intervals: P(|Z| < 1.96 / sqrt(2))), while A's repeat-run interval covers it about 95% of the time.
TEST(Intervals, TheRepeatRunIntervalCoversASecondRunsEstimateAboutAsOftenAsStated) {
  std::mt19937_64 rng(13);
  std::lognormal_distribution<double> sample(0.0, 0.2);
  auto dataset = [&] {
    RoundValues v;
    for (int r = 0; r < 15; ++r) v[r] = sample(rng);
    return v;
  };
  int confidence_covers = 0, repeat_covers = 0;
  const int pairs = 400;
  for (int k = 0; k < pairs; ++k) {
    const RoundValues a = dataset(), b = dataset();
    const Interval ia = RoundBootstrap(rounds(15), 500, static_cast<std::uint64_t>(k) + 1)
                            .interval([&](const std::vector<int>& d) { return median_over(a, d); });
    const double estimate_b = median_over(b, rounds(15));
    confidence_covers += ia.covers(estimate_b);
    repeat_covers += repeat_run(ia).covers(estimate_b);
  }
  EXPECT_LT(static_cast<double>(confidence_covers) / pairs, 0.90);
  EXPECT_GT(static_cast<double>(repeat_covers) / pairs, 0.88);
  EXPECT_LT(static_cast<double>(repeat_covers) / pairs, 0.995);
  const Interval i = repeat_run({2.0, 1.9, 2.2});
  EXPECT_DOUBLE_EQ(i.estimate, 2.0);
  EXPECT_NEAR(i.low, 2.0 - 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(i.high, 2.0 + 0.2 * std::sqrt(2.0), 1e-12);
}

TEST(Intervals, TheSameDataGiveTheSameInterval) {
  const RoundValues v = {{0, 1.0}, {1, 1.4}, {2, 0.9}, {3, 1.2}, {4, 1.1}};
  auto stat = [&](const std::vector<int>& d) { return median_over(v, d); };
  const Interval a = RoundBootstrap(rounds(5)).interval(stat), b = RoundBootstrap(rounds(5)).interval(stat);
  EXPECT_EQ(a.low, b.low);
  EXPECT_EQ(a.high, b.high);
  EXPECT_LE(a.low, a.estimate);
  EXPECT_GE(a.high, a.estimate);
}

}  // namespace
}  // namespace bokeh
