// `compare`'s statistics on synthetic samples with known distributions, and its file checks on
// synthetic results documents. Truth: the Mann-Whitney null distribution in closed form (binomial
// sums, published critical values), the known scale factor between the distributions drawn from,
// and the stated coverage of the interval.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "compare.hpp"

namespace bokeh::compare {
namespace {

using json = nlohmann::json;

double binomial(int n, int k) {
  double c = 1;
  for (int i = 1; i <= k; ++i) c = c * (n - k + i) / i;
  return c;
}

TEST(MannWhitney, CountsAreTheExactNullDistribution) {
  // m = n = 2: the 6 orderings give U = 0, 1, 2, 2, 3, 4.
  EXPECT_EQ(mann_whitney_counts(2, 2), (std::vector<double>{1, 1, 2, 1, 1}));
  for (auto [m, n] : {std::pair{3, 5}, {7, 7}, {10, 4}, {15, 15}}) {
    const auto c = mann_whitney_counts(m, n);
    ASSERT_EQ(c.size(), static_cast<std::size_t>(m * n + 1));
    double sum = 0;
    for (std::size_t u = 0; u < c.size(); ++u) {
      sum += c[u];
      EXPECT_DOUBLE_EQ(c[u], c[c.size() - 1 - u]) << "symmetric about m n / 2";
    }
    EXPECT_NEAR(sum, binomial(m + n, m), 1e-9 * sum) << m << "x" << n;
  }
}

TEST(MannWhitney, CriticalValuesMatchThePublishedTable) {
  // Two-sided alpha = 0.05 critical values of U (reject when U <= value), as tabulated in
  // statistics texts (e.g. Siegel & Castellan, Table J): n1 = n2 = 4..20 and 5 x 10.
  const std::vector<std::tuple<int, int, int>> table = {{4, 4, 0},   {5, 5, 2},   {6, 6, 5},   {7, 7, 8},
                                                        {8, 8, 13},  {9, 9, 17},  {10, 10, 23}, {12, 12, 37},
                                                        {15, 15, 64}, {20, 20, 127}, {5, 10, 8}};
  for (auto [m, n, u] : table) EXPECT_EQ(mann_whitney_critical(m, n, 0.95), u) << m << "x" << n;
  EXPECT_EQ(mann_whitney_critical(3, 3, 0.95), -1) << "3 a side cannot reach 95%";
  EXPECT_EQ(min_samples_for_interval(0.95), 4);
  EXPECT_EQ(min_samples_for_interval(0.99), 5);
}

TEST(MannWhitney, TheNormalApproximationForLargeSamplesAgreesWithTheExactCount) {
  // Used when both samples exceed kExactMaxSamples; checked against the exact counts where both exist.
  for (auto [m, n] : {std::pair{20, 20}, {40, 60}, {50, 50}, {50, 400}}) {
    const int exact = mann_whitney_critical(m, n, 0.95);
    EXPECT_NEAR(mann_whitney_critical_normal(m, n, 0.95), exact, 0.005 * exact + 1) << m << "x" << n;
  }
  EXPECT_EQ(mann_whitney_critical(300, 300, 0.95), mann_whitney_critical_normal(300, 300, 0.95));
  // 300 x 300: mean 45000, sd sqrt(300 * 300 * 601 / 12) = 2123.1, so c ~ 45000 - 1.96 sd - 0.5.
  EXPECT_NEAR(mann_whitney_critical(300, 300, 0.95), 45000 - 1.959964 * 2123.1 - 0.5, 1.0);
}

// n samples of a lognormal with the given median and log-spread, or of a "contended machine":
// a floor plus exponential delays (heavy right tail).
std::vector<double> lognormal(std::mt19937_64& rng, int n, double median, double spread) {
  std::normal_distribution<double> z(0, spread);
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(median * std::exp(z(rng)));
  return v;
}
std::vector<double> contended(std::mt19937_64& rng, int n, double floor_ms, double mean_delay_ms) {
  std::exponential_distribution<double> delay(1 / mean_delay_ms);
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(floor_ms + delay(rng));
  return v;
}

TEST(RatioInterval, CoversTheTrueScaleFactorAsOftenAsItSays) {
  std::mt19937_64 rng(7);
  for (const bool heavy_tail : {false, true}) {
    const double factor = 1.3;
    const int trials = 2000;
    int covered = 0;
    double coverage = 0;
    for (int t = 0; t < trials; ++t) {
      std::vector<double> a = heavy_tail ? contended(rng, 10, 10, 3) : lognormal(rng, 10, 10, 0.1);
      std::vector<double> b = heavy_tail ? contended(rng, 8, 10, 3) : lognormal(rng, 8, 10, 0.1);
      for (double& x : b) x *= factor;  // current = factor * baseline, exactly a scale change
      const RatioInterval r = ratio_interval(a, b, 0.95);
      ASSERT_TRUE(r.exists);
      covered += r.low <= factor && factor <= r.high;
      coverage = r.coverage;
    }
    // The exact coverage of 10 x 8 at 95% is 1 - 2 P(U <= 17) = 0.95658 (enumerating the C(18, 8)
    // orderings); the observed rate within 3 binomial sigmas of it.
    EXPECT_NEAR(coverage, 0.95658, 5e-5);
    const double sigma = std::sqrt(coverage * (1 - coverage) / trials);
    EXPECT_NEAR(static_cast<double>(covered) / trials, coverage, 3 * sigma) << (heavy_tail ? "heavy tail" : "lognormal");
  }
}

TEST(Judge, IdenticalDistributionsGiveNoVerdictOfChange) {
  std::mt19937_64 rng(11);
  int slower = 0, faster = 0, same = 0;
  const int trials = 1000;
  for (int t = 0; t < trials; ++t) {
    const Judgement j = judge(lognormal(rng, 15, 5, 0.05), lognormal(rng, 15, 5, 0.05), Rule{});
    slower += j.verdict == Verdict::slower;
    faster += j.verdict == Verdict::faster;
    same += j.verdict == Verdict::same;
  }
  EXPECT_EQ(slower, 0);
  EXPECT_EQ(faster, 0);
  EXPECT_GT(same, 0.95 * trials) << "15 samples of 5% spread pin the ratio within 10%";
}

TEST(Judge, WithoutAThresholdTheFalseAlarmRateIsTheIntervalsOneSidedError) {
  // threshold 0: slower whenever the interval lies above 1, which happens with probability
  // P(U <= c) <= 2.5% when nothing changed (here 10 x 10: 0.0216).
  std::mt19937_64 rng(13);
  Rule rule;
  rule.threshold = 0;
  int slower = 0;
  const int trials = 4000;
  for (int t = 0; t < trials; ++t)
    slower += judge(contended(rng, 10, 10, 2), contended(rng, 10, 10, 2), rule).verdict == Verdict::slower;
  const double p = 0.0216, sigma = std::sqrt(p * (1 - p) / trials);
  EXPECT_NEAR(static_cast<double>(slower) / trials, p, 3.5 * sigma);
}

TEST(Judge, ShiftedDistributionsGetTheRightVerdict) {
  std::mt19937_64 rng(17);
  for (int t = 0; t < 200; ++t) {
    const auto base = lognormal(rng, 10, 5, 0.05);
    EXPECT_EQ(judge(base, lognormal(rng, 10, 7.5, 0.05), Rule{}).verdict, Verdict::slower);
    EXPECT_EQ(judge(base, lognormal(rng, 10, 5 / 1.5, 0.05), Rule{}).verdict, Verdict::faster);
  }
  // 5% slower with a 10% threshold: within the threshold, so "same" once the interval is narrow.
  const Judgement j = judge(lognormal(rng, 15, 5, 0.01), lognormal(rng, 15, 5.25, 0.01), Rule{});
  EXPECT_EQ(j.verdict, Verdict::same);
  EXPECT_NEAR(j.ratio_of_medians, 1.05, 0.02);
  EXPECT_GT(j.interval.low, 1.0) << "confidently slower, but by less than the threshold";
}

TEST(Judge, TooFewSamplesAreInconclusive) {
  const std::vector<double> four = {1, 1.1, 0.9, 1.05}, doubled = {2, 2.2, 1.8, 2.1};
  Judgement j = judge(four, doubled, Rule{});  // min_samples 5
  EXPECT_EQ(j.verdict, Verdict::inconclusive);
  EXPECT_NE(j.why.find("fewer than 5"), std::string::npos) << j.why;
  EXPECT_NEAR(j.ratio_of_medians, 2.0, 0.05) << "the effect is still reported";
  Rule loose;
  loose.min_samples = 2;
  j = judge({1, 1.1, 0.9}, {2, 2.2, 1.8}, loose);
  EXPECT_EQ(j.verdict, Verdict::inconclusive);
  EXPECT_NE(j.why.find("too few samples"), std::string::npos) << j.why;
  EXPECT_EQ(judge(four, {1, 2, 0, 1, 1}, loose).verdict, Verdict::inconclusive) << "a zero time";
}

// ---- Files ----

json probe(double ms, int rounds) {
  return {{"ms_per_round", std::vector<double>(rounds, ms)}, {"ms", {{"median", ms}}}};
}

// A results document: each point's samples are `ms` times a fixed ripple, probes constant.
json document(const std::vector<std::pair<std::string, double>>& points, double probe_ms = 10) {
  const int rounds = 8;
  const std::vector<double> ripple = {1.00, 1.02, 0.99, 1.01, 0.98, 1.03, 1.00, 0.97};
  json doc = {{"schema", "bokehbench.figure9"},
              {"schema_version", 2},
              {"status", "complete"},
              {"config", json::object()},
              {"context", {{"device", {{"name", "llvmpipe"}, {"type", "cpu"}, {"vendor_id", 1}, {"device_id", 0}}}}},
              {"measurement",
               {{"probes",
                 {{"gpu_copy", probe(probe_ms, rounds)},
                  {"gpu_fma", probe(2 * probe_ms, rounds)},
                  {"cpu_copy", probe(probe_ms, rounds)},
                  {"cpu_fma", probe(probe_ms, rounds)}}}}},
              {"points", json::array()},
              {"skipped", json::array()}};
  for (const auto& [id, ms] : points) {
    std::vector<double> samples;
    std::vector<int> rounds_of;
    for (int r = 0; r < rounds; ++r) samples.push_back(ms * ripple[r]), rounds_of.push_back(r);
    doc["points"].push_back({{"id", id},
                             {"method", id.substr(0, id.find('/'))},
                             {"backend", "gpu"},
                             {"samples_ms", samples},
                             {"sample_rounds", rounds_of},
                             {"work", {{"taps", 100.0}, {"passes", {{"filter", {{"taps", 100.0}}}}}}}});
  }
  return doc;
}

// Sets a probe's recorded work (flops) to `scale` x 1e9.
void base_probe_work(json& doc, const std::string& probe, double scale) {
  doc["measurement"]["probes"][probe]["flops"] = 1e9 * scale;
  doc["measurement"]["probes"][probe]["bytes"] = 0.0;
}

const PointComparison& only(const Report& r) {
  EXPECT_EQ(r.points.size(), 1u);
  return r.points.front();
}

TEST(CompareFiles, NormalisedTimesTakeOutTheMachineRawTimesDoNot) {
  const json base = document({{"naive/gpu/a", 5}}), other_machine = document({{"naive/gpu/a", 10}}, 20);
  Report r = compare_results(base, other_machine, Options{});
  EXPECT_EQ(only(r).judgement.verdict, Verdict::same);
  EXPECT_NEAR(only(r).raw_wall_ratio, 2.0, 1e-12);
  EXPECT_EQ(only(r).times, "wall time, normalised by gpu_copy*gpu_fma");
  EXPECT_EQ(r.exit_code(), kNoRegression);
  Options raw;
  raw.normalise = "none";
  r = compare_results(base, other_machine, raw);
  EXPECT_EQ(only(r).judgement.verdict, Verdict::slower);
  EXPECT_EQ(only(r).times, "wall time, raw");
  EXPECT_EQ(r.exit_code(), kRegression);
}

// Adds process CPU times to a document: each point's wall samples times `cpu_per_wall`.
json with_cpu_times(json doc, double cpu_per_wall) {
  for (auto& p : doc["points"]) {
    json cpu = json::array();
    for (const auto& x : p["samples_ms"]) cpu.push_back(x.get<double>() * cpu_per_wall);
    p["samples_cpu_ms"] = cpu;
  }
  for (auto& [name, probe] : doc["measurement"]["probes"].items()) {
    json cpu = json::array();
    for (const auto& x : probe["ms_per_round"]) cpu.push_back(x.get<double>() * cpu_per_wall);
    probe["cpu_ms_per_round"] = cpu;
  }
  return doc;
}

TEST(CompareFiles, OnACpuDeviceCpuTimeIsComparedWhereBothFilesHaveIt) {
  // Wall time doubled by other processes on the cores; the CPU time (the work) unchanged.
  const json base = with_cpu_times(document({{"naive/gpu/a", 5}}), 2);
  json contended = with_cpu_times(document({{"naive/gpu/a", 5}}), 2);
  for (auto& x : contended["points"][0]["samples_ms"]) x = x.get<double>() * 2;
  Options raw;
  raw.normalise = "none";
  Report r = compare_results(base, contended, raw);
  EXPECT_EQ(r.clock, "cpu");
  EXPECT_EQ(only(r).times, "cpu time, raw");
  EXPECT_EQ(only(r).judgement.verdict, Verdict::same);
  EXPECT_NEAR(only(r).raw_wall_ratio, 2.0, 1e-12);
  EXPECT_NEAR(only(r).raw_cpu_ratio, 1.0, 1e-12);
  raw.times = "wall";
  EXPECT_EQ(only(compare_results(base, contended, raw)).judgement.verdict, Verdict::slower);
  // A file without CPU times: wall, said so.
  r = compare_results(base, document({{"naive/gpu/a", 5}}), Options{});
  EXPECT_EQ(r.clock, "wall");
  EXPECT_NE(fmt::format("{}", fmt::join(r.notes, "|")).find("no samples_cpu_ms"), std::string::npos);
  // On a GPU the timestamps, whatever the files hold.
  json gpu_base = base, gpu_cur = contended;
  gpu_base["context"]["device"]["type"] = gpu_cur["context"]["device"]["type"] = "discrete";
  EXPECT_EQ(compare_results(gpu_base, gpu_cur, Options{}).clock, "wall");
}

TEST(CompareFiles, ProbesAreTakenPerUnitOfTheirWork) {
  // The current run's FMA probe did half the flops (half the threads) in half the time: the same
  // machine speed, so nothing to take out.
  const json base = document({{"naive/gpu/a", 5}});
  json current = document({{"naive/gpu/a", 5}});
  base_probe_work(current, "gpu_fma", 0.5);
  json base_with_work = base;
  base_probe_work(base_with_work, "gpu_fma", 1.0);
  for (auto& x : current["measurement"]["probes"]["gpu_fma"]["ms_per_round"]) x = x.get<double>() / 2;
  const Report r = compare_results(base_with_work, current, Options{});
  EXPECT_NEAR(only(r).judgement.ratio_of_medians, 1.0, 1e-12);
}

TEST(CompareFiles, ExitCodesFollowTheVerdicts) {
  const json base = document({{"naive/gpu/a", 5}, {"flag/gpu/b", 5}});
  EXPECT_EQ(compare_results(base, document({{"naive/gpu/a", 5}, {"flag/gpu/b", 5}}), Options{}).exit_code(), kNoRegression);
  const Report slower = compare_results(base, document({{"naive/gpu/a", 5}, {"flag/gpu/b", 7}}), Options{});
  EXPECT_EQ(slower.exit_code(), kRegression);
  EXPECT_EQ(slower.count(Verdict::slower), 1);
  EXPECT_EQ(slower.count(Verdict::same), 1);
  const Report faster = compare_results(base, document({{"naive/gpu/a", 3}, {"flag/gpu/b", 5}}), Options{});
  EXPECT_EQ(faster.count(Verdict::faster), 1);
  EXPECT_EQ(faster.exit_code(), kNoRegression);
  Options strict;
  strict.rule.min_samples = 20;
  const Report few = compare_results(base, document({{"naive/gpu/a", 50}, {"flag/gpu/b", 5}}), strict);
  EXPECT_EQ(few.count(Verdict::inconclusive), 2);
  EXPECT_EQ(few.exit_code(), kNoRegression) << "inconclusive is not a regression";
  Options loose;
  loose.rule.threshold = 0.5;
  EXPECT_EQ(compare_results(base, document({{"naive/gpu/a", 5}, {"flag/gpu/b", 7}}), loose).exit_code(), kNoRegression)
      << "40% slower, under a 50% threshold";
}

TEST(CompareFiles, ChangedWorkCountersAreAnAlgorithmicChangeWhateverTheTimes) {
  const json base = document({{"naive/gpu/a", 5}});
  json changed = document({{"naive/gpu/a", 5}});
  changed["points"][0]["work"]["passes"]["filter"]["taps"] = 120.0;
  changed["points"][0]["work"]["passes"]["extra"] = {{"taps", 1.0}};
  const Report r = compare_results(base, changed, Options{});
  EXPECT_EQ(only(r).judgement.verdict, Verdict::same);
  ASSERT_EQ(only(r).work_changes.size(), 2u);
  EXPECT_EQ(only(r).work_changes[0], "passes.filter.taps: 100.0 -> 120.0");
  EXPECT_EQ(only(r).work_changes[1], "passes.extra: added ({\"taps\":1.0})");
  EXPECT_EQ(r.exit_code(), kWorkChanged);
  changed["points"][0]["samples_ms"] = document({{"naive/gpu/a", 8}})["points"][0]["samples_ms"];
  EXPECT_EQ(compare_results(base, changed, Options{}).exit_code(), kRegression) << "a regression outranks it";
}

TEST(CompareFiles, MismatchesAreReportedNotCompared) {
  const json base = document({{"naive/gpu/a", 5}, {"flag/gpu/b", 5}});
  auto mismatch = [&](const json& current, const std::string& expected) {
    const Report r = compare_results(base, current, Options{});
    EXPECT_EQ(r.exit_code(), kNotComparable) << expected;
    std::string all;
    for (const auto& m : r.mismatches) all += m + "\n";
    EXPECT_NE(all.find(expected), std::string::npos) << all;
    return r;
  };
  json other = base;
  other["schema"] = "bokehbench.tradeoff";
  mismatch(other, "schema: baseline 'bokehbench.figure9', current 'bokehbench.tradeoff'");
  other = base;
  other["schema_version"] = 1;
  mismatch(other, "schema_version: baseline 2, current 1");
  mismatch(document({{"naive/gpu/a", 5}}), "methods: only in baseline [flag]");
  mismatch(document({{"naive/gpu/a", 5}, {"flag/gpu/b", 5}, {"flag/gpu/c", 5}}), "points only in current (1): flag/gpu/c");
  other = document({{"naive/gpu/a", 5}});
  other["skipped"].push_back({{"id", "flag/gpu/b"}, {"method", "flag"}, {"reason", "over budget"}});
  const Report r = mismatch(other, "flag/gpu/b: measured in baseline, skipped in current (over budget)");
  EXPECT_EQ(r.points.size(), 1u) << "the points both measured are still compared";
}

TEST(CompareFiles, AnotherMachinesTimingsAreInformationNeverAVerdict) {
  // Issue 17: unchanged code failed CI on another CPU kind. Files from two machines are compared,
  // verdicts shown, and the exit status is not the machine's doing.
  const json base = document({{"naive/gpu/a", 5}, {"flag/gpu/b", 5}});
  for (const auto& [key, value] : {std::pair<std::string, json>{"cpu_model", "another CPU"}, {"cpu_cores", 64}}) {
    json other = document({{"naive/gpu/a", 9}, {"flag/gpu/b", 5}});  // 1.8x slower
    other["context"][key] = value;
    const Report r = compare_results(base, other, Options{});
    EXPECT_EQ(r.count(Verdict::slower), 1) << key;
    ASSERT_EQ(r.machine_differences.size(), 1u) << key;
    EXPECT_NE(r.machine_differences[0].find(key), std::string::npos);
    EXPECT_EQ(r.exit_code(), kNoRegression) << key;
    EXPECT_NE(report_text(r).find("information, not a regression"), std::string::npos);
  }
  json gpu = base;
  gpu["context"]["device"]["name"] = "NVIDIA H200";
  const Report r = compare_results(base, gpu, Options{});
  EXPECT_TRUE(r.mismatches.empty());
  EXPECT_EQ(r.machine_differences.at(0), "device name: baseline llvmpipe, current NVIDIA H200");
  EXPECT_EQ(r.exit_code(), kNoRegression);
}

TEST(SignedRank, CountsAreTheExactNullDistribution) {
  // {1, 2, 3}: subsets sum to 0, 1, 2, 3 (twice: {3}, {1, 2}), 4, 5, 6.
  EXPECT_EQ(signed_rank_counts(3), (std::vector<double>{1, 1, 1, 2, 1, 1, 1}));
  for (int n : {5, 12, 30}) {
    const auto c = signed_rank_counts(n);
    double total = 0;
    for (double v : c) total += v;
    EXPECT_EQ(total, std::ldexp(1.0, n)) << n;  // every subset once
    for (std::size_t t = 0; t < c.size(); ++t) EXPECT_EQ(c[t], c[c.size() - 1 - t]) << n;  // symmetric
  }
}

TEST(SignedRank, CriticalValuesMatchThePublishedTable) {
  // Two-sided 5% critical values of the Wilcoxon signed-rank statistic (e.g. Siegel & Castellan,
  // Table H), n = 5 has none.
  EXPECT_EQ(signed_rank_critical(5, 0.95), -1);
  const std::vector<std::pair<int, int>> table = {{6, 0},   {7, 2},   {8, 3},   {9, 5},   {10, 8},  {11, 10},
                                                  {12, 13}, {13, 17}, {14, 21}, {15, 25}, {20, 52}, {25, 89}};
  for (auto [n, c] : table) EXPECT_EQ(signed_rank_critical(n, 0.95), c) << n;
}

TEST(PairedInterval, CoversTheTrueRatioAsOftenAsItSaysWhileTheMachineDrifts) {
  // Each pair shares a machine speed drawn anew (drift up to 2x between pairs): the paired interval
  // is as tight as the within-pair noise, and covers the true ratio at its exact coverage.
  std::mt19937_64 rng(11);
  std::lognormal_distribution<double> machine(0.0, 0.3), noise(0.0, 0.03);
  const double factor = 1.1;
  const int trials = 2000, n = 10;
  int covered = 0;
  double coverage = 0, width = 0;
  for (int t = 0; t < trials; ++t) {
    std::vector<double> a, b;
    for (int r = 0; r < n; ++r) {
      const double speed = machine(rng);
      a.push_back(5 * speed * noise(rng));
      b.push_back(5 * factor * speed * noise(rng));
    }
    const RatioInterval ci = paired_ratio_interval(a, b, 0.95);
    ASSERT_TRUE(ci.exists);
    covered += ci.low <= factor && factor <= ci.high;
    coverage = ci.coverage;
    width += std::log(ci.high / ci.low) / trials;
  }
  // n = 10, c = 8: 1 - 2 P(T <= 8) = 1 - 2 * 25 / 1024.
  EXPECT_NEAR(coverage, 1 - 50.0 / 1024, 1e-12);
  const double sigma = std::sqrt(coverage * (1 - coverage) / trials);
  EXPECT_NEAR(static_cast<double>(covered) / trials, coverage, 3 * sigma);
  EXPECT_LT(width, 0.1) << "the machine's 30% spread between pairs must cancel";
}

TEST(JudgePaired, VerdictsFollowTheInterval) {
  const std::vector<double> base = {10, 12, 9, 15, 11, 10, 13, 9};
  auto scaled = [&](double f, double jitter) {
    std::vector<double> v;
    for (std::size_t r = 0; r < base.size(); ++r) v.push_back(base[r] * f * (1 + jitter * ((r % 3) - 1.0)));
    return v;
  };
  const Rule rule{0.05, 0.95, 6};
  EXPECT_EQ(judge_paired(base, scaled(1.0, 0.01), rule).verdict, Verdict::same);
  EXPECT_EQ(judge_paired(base, scaled(1.2, 0.01), rule).verdict, Verdict::slower);
  EXPECT_EQ(judge_paired(base, scaled(0.8, 0.01), rule).verdict, Verdict::faster);
  EXPECT_EQ(judge_paired(base, scaled(1.05, 0.05), rule).verdict, Verdict::inconclusive);
  const Judgement exact = judge_paired(base, scaled(1.2, 0), rule);
  EXPECT_NEAR(exact.ratio_of_medians, 1.2, 1e-12);
  EXPECT_NEAR(exact.interval.low, 1.2, 1e-12);
  EXPECT_NEAR(exact.interval.high, 1.2, 1e-12);
  const Judgement few = judge_paired({1, 2, 3}, {1, 2, 3}, rule);
  EXPECT_EQ(few.verdict, Verdict::inconclusive);
  EXPECT_EQ(few.why, "3 pairs, fewer than 6");
}

TEST(CompareFiles, MalformedFilesNameTheFileAndTheKey) {
  const json base = document({{"naive/gpu/a", 5}});
  auto error = [&](const json& current) {
    try {
      compare_results(base, current, Options{}, "base.json", "cur.json");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  json broken = base;
  broken["points"][0].erase("samples_ms");
  EXPECT_EQ(error(broken), "cur.json: point 'naive/gpu/a': 'samples_ms' is missing");
  broken = base;
  broken["points"][0]["samples_ms"][2] = "fast";
  EXPECT_EQ(error(broken), "cur.json: point 'naive/gpu/a': 'samples_ms[2]' is not a number");
  broken = base;
  broken["points"][0]["sample_rounds"][0] = 99;
  EXPECT_NE(error(broken).find("sample_rounds[0] = 99 is not one of the 8 rounds"), std::string::npos) << error(broken);
  broken = base;
  broken["measurement"]["probes"].erase("gpu_fma");
  EXPECT_NE(error(broken).find("needs probe 'gpu_fma'"), std::string::npos) << error(broken);
  broken = base;
  broken["points"] = "none";
  EXPECT_EQ(error(broken), "cur.json: 'points' is not an array (it is string)");
  broken = base;
  broken.erase("schema_version");
  EXPECT_EQ(error(broken), "cur.json: 'schema_version' is missing");
}

}  // namespace
}  // namespace bokeh::compare
