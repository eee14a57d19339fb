#pragma once
// Intervals for the figures a person reads (medians, ratios, growth exponents), drawn from the
// rounds of an interleaved run (runner.hpp). A round visits every point once, close in time, so the
// machine's drift moves a round's samples together: the bootstrap resamples whole rounds. That keeps
// the correlation a paired figure relies on (a ratio of two points measured side by side in each
// round) instead of treating samples as independent, and it widens an interval when rounds disagree.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
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

// Where a repeat run on the same machine would put its estimate, at 95%: this run's interval
// widened by sqrt(2) on each side (the difference of two runs of equal spread has sqrt(2) times
// one run's standard error). "Run B's estimate lies in run A's confidence interval" is a weaker
// event than it looks: for calibrated 95% intervals it happens about 83% of the time (|Z| < 1.96 /
// sqrt(2)), so of 18 figures about 3 miss by chance alone; this interval is the one to hold a
// repeat run to.
Interval repeat_run(const Interval& confidence);

// One point's samples by the round they were taken in (one per round at most).
using RoundValues = std::map<int, double>;

// The median of `values` over `rounds`, a multiset (a round drawn twice counts twice); NaN when
// none of those rounds has a value.
double median_over(const RoundValues& values, const std::vector<int>& rounds);
// The median over `rounds` of a / b, taken within each round that has both: the paired ratio.
double paired_ratio(const RoundValues& a, const RoundValues& b, const std::vector<int>& rounds);

// A results point's samples by round: `field` (samples_ms, samples_cpu_ms) against sample_rounds.
RoundValues round_values(const nlohmann::json& point, const char* field = "samples_ms");

// Percentile bootstrap over rounds at 95%.
class RoundBootstrap {
 public:
  // `resamples` draws of rounds.size() rounds with replacement, seeded: the same data give the same
  // intervals.
  explicit RoundBootstrap(std::vector<int> rounds, int resamples = 1000, std::uint64_t seed = 1);
  // `statistic` of a multiset of rounds: its value on all rounds is the estimate; the interval spans
  // the 2.5% and 97.5% quantiles over the resamples (those where it is not finite are left out; with
  // none left, the interval is the estimate alone).
  Interval interval(const std::function<double(const std::vector<int>& rounds)>& statistic) const;
  const std::vector<int>& rounds() const { return rounds_; }

 private:
  std::vector<int> rounds_;
  std::vector<std::vector<int>> draws_;
};

// The paired ratio a / b over every round either has, with its interval; nullopt when they share
// no round.
std::optional<Interval> paired_ratio_interval(const RoundValues& a, const RoundValues& b);

}  // namespace bokeh
