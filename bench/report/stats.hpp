#pragma once
// Fits used in reports.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace bokeh {

struct PowerLawFit {
  double exponent = 0;     // b in t = a * N^b
  double coefficient = 0;  // a
  double r_squared = 0;    // of the log-log line
  int points = 0;
};

// Least squares on (log x, log y). Needs at least two distinct positive x.
inline PowerLawFit fit_power_law(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size() || x.size() < 2) throw std::invalid_argument("power-law fit needs >= 2 points");
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (x[i] <= 0 || y[i] <= 0) throw std::invalid_argument("power-law fit needs positive values");
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, syy += ly * ly;
  }
  const double var_x = sxx - sx * sx / n, cov = sxy - sx * sy / n, var_y = syy - sy * sy / n;
  if (var_x <= 0) throw std::invalid_argument("power-law fit needs distinct x values");
  PowerLawFit fit;
  fit.exponent = cov / var_x;
  fit.coefficient = std::exp((sy - fit.exponent * sx) / n);
  fit.r_squared = var_y > 0 ? cov * cov / (var_x * var_y) : 1.0;
  fit.points = static_cast<int>(x.size());
  return fit;
}

// Pareto front of (cost, quality): indices of the points that nothing beats on both, cheapest first.
// A costlier point joins only if its quality exceeds the best so far by more than `same_quality`
// (so measurement noise does not put equivalent configurations on the front).
inline std::vector<std::size_t> pareto_front(const std::vector<double>& cost, const std::vector<double>& quality,
                                             double same_quality = 0.0) {
  if (cost.size() != quality.size()) throw std::invalid_argument("pareto_front: sizes differ");
  std::vector<std::size_t> order(cost.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) {
    return cost[a] < cost[b] || (cost[a] == cost[b] && quality[a] > quality[b]);
  });
  std::vector<std::size_t> front;
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t i : order)
    if (front.empty() || quality[i] > best + same_quality) front.push_back(i), best = quality[i];
  return front;
}

}  // namespace bokeh
