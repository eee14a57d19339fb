#pragma once
// Intervals for the figures a person reads (medians, ratios, growth exponents), drawn from the
// rounds of an interleaved run (runner.hpp). Every such figure is the median over rounds of a value
// taken within each round: a point's frame time, a ratio of two points measured side by side (the
// machine's drift, which moves a round's samples together, cancels in it), a growth exponent fitted
// to one round's curve. Its interval is the distribution-free one for a median, from the rounds'
// order statistics: exact for independent rounds at any sample size. (A percentile bootstrap over
// rounds, used before, ran narrow at the 10-20 rounds a figure9 point gets: two default runs'
// repeat-run intervals covered each other's estimates for 13 of 18 figures; these for 16 of 18.)
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bokeh {

struct Interval {
  double estimate = 0, low = 0, high = 0;  // the statistic of all rounds; 2.5% and 97.5% of its resamples
  double half_width() const { return (high - low) / 2; }
  double relative_half_width() const;  // half_width / |estimate|; infinite when the estimate is 0
  bool covers(double value) const { return low <= value && value <= high; }
};
nlohmann::json interval_json(const Interval& interval);  // {"estimate", "low", "high"}
// "estimate [low-high]" of an interval_json, `decimals` after the point.
std::string interval_text(const nlohmann::json& interval, int decimals = 1);

// Where a repeat run on the same machine would put its estimate, at 95%: this run's interval
// widened by sqrt(2) on each side (the difference of two runs of equal spread has sqrt(2) times
// one run's standard error). "Run B's estimate lies in run A's confidence interval" is a weaker
// event than it looks: for calibrated 95% intervals it happens about 83% of the time (|Z| < 1.96 /
// sqrt(2)), so of 18 figures about 3 miss by chance alone; this interval is the one to hold a
// repeat run to.
// `run_to_run_sd`: the standard deviation of this figure's estimates over the machine's earlier runs
// of the same configuration, with `degrees_of_freedom` (history::run_to_run_spread), in the figure's
// units. A shared machine's runs differ by more than one run's rounds can show: over six
// default figure9 runs on a 2-core VM the 18 figures spread 1.4x (median; 0.4-2.7x) the standard error
// each run's own interval implies, while within a run the rounds showed no drift (their batch means
// varied as independent rounds' would). Where it is wider than this run's own, each side is sqrt(2) *
// t * run_to_run_sd, t the 97.5% quantile of Student's t with `degrees_of_freedom` (runs less one; a
// standard deviation from 3 runs is itself uncertain: t = 4.30 there, 2.26 from 10). It stands for a
// whole run's uncertainty (rounds and run-level offset), so it replaces this run's side rather than
// adding to it. Held to 11 default runs (every pair, with 3 or 5 others drawn as its history), pairs
// agreed on 93% of figures this way, 87-90% with 1.96 in place of t, 68% from the rounds alone.
Interval repeat_run(const Interval& confidence, double run_to_run_sd = 0, int degrees_of_freedom = 0);

// The 97.5% quantile of Student's t distribution with `degrees_of_freedom` (>= 1): its density
// integrated numerically (Simpson) and the quantile found by bisection, to 1e-6.
double student_t_975(int degrees_of_freedom);

// One point's samples by the round they were taken in (one per round at most).
using RoundValues = std::map<int, double>;

// A results point's samples by round: `field` (samples_ms, samples_cpu_ms) against sample_rounds.
RoundValues round_values(const nlohmann::json& point, const char* field = "samples_ms");

// The median of `values` (one a round) with its 95% interval: the order statistics x(k) and
// x(n + 1 - k), k the largest with P(Binomial(n, 1/2) < k) <= 2.5%, so the true median lies between
// them with probability >= 95% whatever the distribution (n >= 6; below, [min, max] at
// 1 - 2^(1 - n)). Non-finite values are left out; none left: NaN.
Interval median_interval(std::vector<double> values);
Interval median_interval(const RoundValues& values);

// The median over the rounds both have of a / b, with its interval; nullopt when they share no
// round.
std::optional<Interval> paired_ratio_interval(const RoundValues& a, const RoundValues& b);

// Every point (and baseline) of a sweep document gets `frame_ms_interval`: its median frame time with the 95%
// interval above, from its samples (one a round), and `pass_ms_interval`, the same for each timed
// pass. Written when a sweep ends and by `merge`, so results measured before it gain them from
// their samples.
void add_median_intervals(nlohmann::json& doc);

}  // namespace bokeh
