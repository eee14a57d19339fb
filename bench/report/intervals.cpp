#include "intervals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "runner.hpp"

namespace bokeh {

double Interval::relative_half_width() const {
  return estimate != 0 ? half_width() / std::abs(estimate) : std::numeric_limits<double>::infinity();
}

nlohmann::json interval_json(const Interval& interval) {
  return {{"estimate", interval.estimate}, {"low", interval.low}, {"high", interval.high}};
}

std::string interval_text(const nlohmann::json& interval, int decimals) {
  return fmt::format("{:.{}f} [{:.{}f}-{:.{}f}]", interval["estimate"].get<double>(), decimals,
                     interval["low"].get<double>(), decimals, interval["high"].get<double>(), decimals);
}

Interval repeat_run(const Interval& confidence, double run_to_run_sd) {
  const double widen = std::sqrt(2.0), spread = 1.96 * run_to_run_sd;
  return {confidence.estimate, confidence.estimate - widen * std::max(confidence.estimate - confidence.low, spread),
          confidence.estimate + widen * std::max(confidence.high - confidence.estimate, spread)};
}

RoundValues round_values(const nlohmann::json& point, const char* field) {
  RoundValues out;
  const auto& values = point[field];
  for (std::size_t i = 0; i < values.size(); ++i) out[point["sample_rounds"][i].get<int>()] = values[i].get<double>();
  return out;
}

Interval median_interval(std::vector<double> values) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (values.empty()) return {nan, nan, nan};
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  // B ~ Binomial(n, 1/2): the number of rounds below the true median.
  std::size_t k = 1;      // [min, max] when even P(B < 1) = 2^-n exceeds 2.5% (n < 6)
  double cumulative = 0;  // P(B <= j), summed in logs (n may be in the hundreds)
  for (std::size_t j = 0; 2 * (j + 1) <= n; ++j) {
    cumulative += std::exp(std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) - n * std::log(2.0));
    if (cumulative > 0.025) break;
    k = j + 1;  // P(B < k) = P(B <= j) <= 2.5%
  }
  return {runner::quantile(values, 0.5), values[k - 1], values[n - k]};
}

Interval median_interval(const RoundValues& values) {
  std::vector<double> v;
  for (const auto& [round, value] : values) v.push_back(value);
  return median_interval(std::move(v));
}

std::optional<Interval> paired_ratio_interval(const RoundValues& a, const RoundValues& b) {
  std::vector<double> ratios;
  for (const auto& [round, value] : a)
    if (auto it = b.find(round); it != b.end() && it->second > 0) ratios.push_back(value / it->second);
  if (ratios.empty()) return std::nullopt;
  return median_interval(std::move(ratios));
}

void add_median_intervals(nlohmann::json& doc) {
  for (auto& point : doc["points"]) {
    if (!point.contains("samples_ms") || point["samples_ms"].empty()) continue;
    point["frame_ms_interval"] = interval_json(median_interval(round_values(point)));
    nlohmann::json passes = nlohmann::json::object();
    if (point.contains("samples_pass_ms"))
      for (const auto& [pass, samples] : point["samples_pass_ms"].items())
        passes[pass] = interval_json(median_interval(samples.get<std::vector<double>>()));
    point["pass_ms_interval"] = passes;
  }
}

}  // namespace bokeh
