#include "intervals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "runner.hpp"

namespace bokeh {

double Interval::relative_half_width() const {
  return estimate != 0 ? half_width() / std::abs(estimate) : std::numeric_limits<double>::infinity();
}

nlohmann::json interval_json(const Interval& interval) {
  return {{"estimate", interval.estimate}, {"low", interval.low}, {"high", interval.high}};
}

Interval repeat_run(const Interval& confidence) {
  const double widen = std::sqrt(2.0);
  return {confidence.estimate, confidence.estimate - widen * (confidence.estimate - confidence.low),
          confidence.estimate + widen * (confidence.high - confidence.estimate)};
}

double median_over(const RoundValues& values, const std::vector<int>& rounds) {
  std::vector<double> drawn;
  for (int r : rounds)
    if (auto it = values.find(r); it != values.end()) drawn.push_back(it->second);
  return drawn.empty() ? std::numeric_limits<double>::quiet_NaN() : runner::quantile(std::move(drawn), 0.5);
}

double paired_ratio(const RoundValues& a, const RoundValues& b, const std::vector<int>& rounds) {
  std::vector<double> ratios;
  for (int r : rounds) {
    const auto x = a.find(r), y = b.find(r);
    if (x != a.end() && y != b.end() && y->second > 0) ratios.push_back(x->second / y->second);
  }
  return ratios.empty() ? std::numeric_limits<double>::quiet_NaN() : runner::quantile(std::move(ratios), 0.5);
}

RoundValues round_values(const nlohmann::json& point, const char* field) {
  RoundValues out;
  const auto& values = point[field];
  for (std::size_t i = 0; i < values.size(); ++i) out[point["sample_rounds"][i].get<int>()] = values[i].get<double>();
  return out;
}

RoundBootstrap::RoundBootstrap(std::vector<int> rounds, int resamples, std::uint64_t seed) : rounds_(std::move(rounds)) {
  if (rounds_.empty()) return;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, rounds_.size() - 1);
  draws_.resize(static_cast<std::size_t>(resamples));
  for (auto& draw : draws_) {
    draw.resize(rounds_.size());
    for (int& r : draw) r = rounds_[pick(rng)];
  }
}

Interval RoundBootstrap::interval(const std::function<double(const std::vector<int>& rounds)>& statistic) const {
  Interval out;
  out.estimate = out.low = out.high = statistic(rounds_);
  std::vector<double> values;
  for (const auto& draw : draws_)
    if (const double v = statistic(draw); std::isfinite(v)) values.push_back(v);
  if (!values.empty()) {
    out.low = runner::quantile(values, 0.025);
    out.high = runner::quantile(values, 0.975);
  }
  return out;
}

std::optional<Interval> paired_ratio_interval(const RoundValues& a, const RoundValues& b) {
  std::vector<int> shared;
  for (const auto& [round, value] : a)
    if (b.count(round)) shared.push_back(round);
  if (shared.empty()) return std::nullopt;
  return RoundBootstrap(shared).interval([&](const std::vector<int>& d) { return paired_ratio(a, b, d); });
}

}  // namespace bokeh
