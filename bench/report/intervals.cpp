#include "intervals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

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

Interval repeat_run(const Interval& confidence, double run_to_run_sd, int degrees_of_freedom) {
  const double widen = std::sqrt(2.0);
  const double spread = degrees_of_freedom >= 1 ? student_t_975(degrees_of_freedom) * run_to_run_sd : 0;
  return {confidence.estimate, confidence.estimate - widen * std::max(confidence.estimate - confidence.low, spread),
          confidence.estimate + widen * std::max(confidence.high - confidence.estimate, spread)};
}

double student_t_975(int degrees_of_freedom) {
  if (degrees_of_freedom < 1) throw std::invalid_argument("student_t_975: degrees of freedom must be >= 1");
  const double nu = degrees_of_freedom;
  const double log_norm = std::lgamma((nu + 1) / 2) - std::lgamma(nu / 2) - 0.5 * std::log(nu * std::acos(-1.0));
  auto density = [&](double t) { return std::exp(log_norm - (nu + 1) / 2 * std::log1p(t * t / nu)); };
  auto mass_from_zero = [&](double x) {  // P(0 < T < x), Simpson's rule
    const int steps = 4000;
    const double h = x / steps;
    double sum = density(0) + density(x);
    for (int i = 1; i < steps; ++i) sum += (i % 2 ? 4 : 2) * density(i * h);
    return sum * h / 3;
  };
  double low = 0, high = 20;  // t(1) = 12.71
  while (high - low > 1e-7) {
    const double mid = (low + high) / 2;
    (mass_from_zero(mid) < 0.475 ? low : high) = mid;
  }
  return (low + high) / 2;
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
  for (const char* points : {"points", "baselines"}) {  // baselines: figure9's CPU baseline (SweepSettings::Baseline)
    if (!doc.contains(points)) continue;
    for (auto& point : doc[points]) {
      if (!point.contains("samples_ms") || point["samples_ms"].empty()) continue;
      point["frame_ms_interval"] = interval_json(median_interval(round_values(point)));
      nlohmann::json passes = nlohmann::json::object();
      if (point.contains("samples_pass_ms"))
        for (const auto& [pass, samples] : point["samples_pass_ms"].items())
          passes[pass] = interval_json(median_interval(samples.get<std::vector<double>>()));
      point["pass_ms_interval"] = passes;
    }
  }
}

}  // namespace bokeh
