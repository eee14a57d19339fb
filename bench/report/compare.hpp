#pragma once
// Regression verdicts between two sweep results files (`bokehbench compare`).
//
// The statistic: per point, the factor s with current ~ s * baseline (a scale change; times are
// positive and slowdowns multiply). Its interval is the exact distribution-free one that inverts the
// Mann-Whitney test on log times: the pairwise ratios current_j / baseline_i, from the (c+1)-th
// smallest to the (c+1)-th largest, c the two-sided critical count of U at the confidence asked
// (Hodges & Lehmann 1963; Bauer 1972). It holds for any continuous distribution of sample times
// (no normality, outliers count once), and its coverage is exact for small samples, where a
// bootstrap of the median is not: at 95% it exists from 4 samples a side, and the runner takes
// at least 5. The effect shown is the ratio of the medians.
//
// Verdicts, with t the threshold (0.10: 10%) and [low, high] the interval:
//   slower        low > 1 + t          confidently slower by more than t (a regression)
//   faster        high < 1 / (1 + t)   confidently faster by more than t
//   same          the whole interval within [1 / (1 + t), 1 + t]
//   inconclusive  anything else, or fewer than min_samples samples on a side
// The interval covers sampling noise within each run; what differs between two runs as a whole
// (another machine, another boot) is systematic and is what the threshold absorbs. `selftest-
// compare` measures the false-alarm and detection rates that result on a given machine.
//
// Which time: on lavapipe (a CPU device), the process CPU time of each sample by default: the work
// done, which other processes on a shared machine do not inflate (measured here: within-run spread
// 2-3% against 35-65% for wall-clock time at a load average of 10 on 2 cores). On a real GPU, the
// timestamps (wall). And normalised by default: each sample divided by the calibration probes timed
// in the same round (the geometric mean of the copy and FMA kernels on the point's backend, per unit
// of their work), which takes out the machine's speed, e.g. CI's VM against the baseline's.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bokeh::compare {

// The process exit status of `bokehbench compare`, most serious first when several apply.
enum ExitCode : int {
  kNoRegression = 0,  // every point same, faster or inconclusive; work unchanged
  kError = 1,         // unreadable or malformed file (bad arguments: CLI11's own codes, 100 and up)
  kRegression = 2,    // at least one point confidently slower by more than the threshold
  kNotComparable = 3, // other schema, device, method set or points: nothing or not everything compared
  kWorkChanged = 4,   // no regression, but a point's work counters differ: an algorithmic change
};

// ---- The statistic, on plain samples ----

// Exact null distributions are used while the smaller sample has at most this many values; beyond,
// the normal approximation (accurate to a count or two there).
constexpr int kExactMaxSamples = 50;

// Number of arrangements of m baseline and n current values giving Mann-Whitney count
// U = #{(i, j): current_j < baseline_i} = u, for u = 0 .. m n (the exact null distribution, no ties);
// they sum to C(m + n, m).
std::vector<double> mann_whitney_counts(int m, int n);

// The largest c with P(U <= c) <= (1 - confidence) / 2 under the null, or -1 when even P(U = 0)
// exceeds it (too few samples for an interval at that confidence).
int mann_whitney_critical(int m, int n, double confidence);

// The same from the normal approximation with continuity correction (used beyond kExactMaxSamples).
int mann_whitney_critical_normal(int m, int n, double confidence);

// The fewest samples per side (equal sizes) for which an interval at `confidence` exists.
int min_samples_for_interval(double confidence);

struct RatioInterval {
  bool exists = false;  // false: too few samples for the confidence asked
  double low = 0, high = 0;
  double coverage = 0;  // exact: 1 - 2 P(U <= c), at least the confidence asked
};

// Interval for s in current = s * baseline, all values > 0.
RatioInterval ratio_interval(const std::vector<double>& baseline, const std::vector<double>& current,
                             double confidence);

enum class Verdict { same, faster, slower, inconclusive };
std::string to_string(Verdict v);

struct Rule {
  double threshold = 0.10;   // the smallest change that matters (0.10: 10%)
  double confidence = 0.95;  // of the interval
  int min_samples = 5;       // per side; fewer give `inconclusive`
};

struct Judgement {
  Verdict verdict = Verdict::inconclusive;
  double ratio_of_medians = 0;  // current / baseline
  RatioInterval interval;
  std::string why;  // for inconclusive: what is missing
};

Judgement judge(const std::vector<double>& baseline, const std::vector<double>& current, const Rule& rule);

// ---- Paired samples (bokehbench ab: baseline and candidate timed back to back, round by round) ----
//
// Per pair r the log-ratio d_r = log(current_r / baseline_r); what the machine did during that
// pair (its clock, a neighbour's burst, slow drift) is in both and cancels. The interval is the
// exact distribution-free one for the centre of the d_r that inverts the Wilcoxon signed-rank test:
// the Walsh averages (d_i + d_j) / 2, i <= j, from the (c+1)-th smallest to the (c+1)-th largest, c
// the two-sided critical value of the signed-rank statistic (Hodges & Lehmann 1963). It assumes the
// d_r are independent and symmetric about their centre, which alternating which side goes first
// makes so; the estimate is the median of the Walsh averages. At 95% it exists from 6 pairs.

// Number of subsets of {1 .. n} with sum s, for s = 0 .. n (n + 1) / 2 (the exact null distribution
// of the signed-rank statistic, times 2^n).
std::vector<double> signed_rank_counts(int n);
// The largest c with P(T <= c) <= (1 - confidence) / 2 under the null, or -1 when n is too small.
int signed_rank_critical(int n, double confidence);
// Interval for s in current_r = s * baseline_r (same length, all values > 0).
RatioInterval paired_ratio_interval(const std::vector<double>& baseline, const std::vector<double>& current,
                                    double confidence);
// The verdict from paired samples (Rule::min_samples: the fewest pairs); ratio_of_medians holds
// the Hodges-Lehmann estimate exp(median of the Walsh averages).
Judgement judge_paired(const std::vector<double>& baseline, const std::vector<double>& current, const Rule& rule);

// ---- Two results files ----

struct Options {
  Rule rule;
  // Which time: "wall" (GPU timestamps, or the wall clock of the CPU references), "cpu" (the
  // process's CPU time over each sample: the work done, which other processes competing for the
  // cores do not inflate; meaningful where the device is the CPU, i.e. lavapipe), or "auto": cpu
  // when the device is a CPU device and both files have it, else wall.
  std::string times = "auto";
  // "auto": each point by its backend's probes (gpu_copy and gpu_fma, or cpu_copy and cpu_fma), per
  // unit of their work; "none": raw times; else a comma-separated list of probe names for every point.
  std::string normalise = "auto";
};

struct PointComparison {
  std::string id;
  Judgement judgement;    // of the compared times (Report::clock, normalised or not)
  std::string times;      // e.g. "cpu time normalised by gpu_copy*gpu_fma", "wall time, raw"
  double raw_wall_ratio = 0, raw_cpu_ratio = 0;  // ratios of medians of the raw times (0: not recorded)
  int baseline_samples = 0, current_samples = 0;
  double baseline_median_ms = 0, current_median_ms = 0;  // wall
  std::vector<std::string> work_changes;  // "passes.horizontal.taps: 1200 -> 1500"
  // Paired design: the compared times pair by pair (taken back to back), for a second look.
  std::vector<double> paired_baseline_ms, paired_current_ms;
  // Paired design: each side's raw samples per frame, wall and process CPU time (the results store's).
  std::vector<double> wall_ms[2], cpu_ms[2];
  std::string method, backend;
};

struct Report {
  // "files": two results files (compare); "paired": two builds timed back to back in one run (ab).
  std::string design = "files";
  std::string baseline_path, current_path;
  Options options;
  std::string clock;  // the time compared: "wall" or "cpu"
  std::vector<std::string> mismatches;  // why the files are not comparable (as a whole)
  std::vector<std::string> notes;       // differences that do not stop the comparison
  // The files come from different machines (device, CPU model, cores or LP_NUM_THREADS differ):
  // their timings are shown as information, and no verdict sets the exit status (0 unless the files
  // are not comparable at all). Two builds are compared on one machine with `bokehbench ab`.
  std::vector<std::string> machine_differences;
  std::vector<PointComparison> points;  // the points both files measured
  // Paired design: each build's run context (its worker's hello), for the results store.
  nlohmann::json contexts[2];
  int count(Verdict v) const;
  bool work_changed() const;
  int exit_code() const;
};

// Reads a results file; throws std::runtime_error naming the file and what is wrong with it.
nlohmann::json load_results(const std::string& path);

// Compares two loaded results files. Throws std::runtime_error (naming the file and the key) when
// one is malformed; differences that make them incomparable go to Report::mismatches instead.
Report compare_results(const nlohmann::json& baseline, const nlohmann::json& current, const Options& options,
                       const std::string& baseline_path = "baseline", const std::string& current_path = "current");

// "a.b.c: old -> new" for every leaf that differs between two JSON values (work counters).
std::vector<std::string> json_differences(const nlohmann::json& baseline, const nlohmann::json& current);

nlohmann::json report_json(const Report& report);
std::string report_text(const Report& report);

}  // namespace bokeh::compare
