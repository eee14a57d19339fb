#include "changepoints.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace bokeh::history {

namespace {

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Best {
  std::size_t tau = 0;
  double q = 0;
};

Best best_split(const std::vector<double>& x, int min_segment) {
  const std::vector<double> q = energy_statistics(x, min_segment);
  Best best;
  for (std::size_t t = 0; t < q.size(); ++t)
    if (q[t] > best.q) best = {t, q[t]};
  return best;
}

}  // namespace

std::vector<double> energy_statistics(const std::vector<double>& x, int min_segment) {
  const std::size_t n = x.size();
  std::vector<double> q(n, 0.0);
  const std::size_t min_size = static_cast<std::size_t>(std::max(min_segment, 2));
  if (n < 2 * min_size) return q;
  // col[t] = sum_{i<t} |x_i - x_t|, row[t] = sum_{j>t} |x_t - x_j|: the distances of x_t to either side.
  std::vector<double> to_left(n, 0.0), to_right(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const double d = std::abs(x[i] - x[j]);
      to_right[i] += d;
      to_left[j] += d;
    }
  // within_left(t): sum over pairs in x[0..t); within_right(t): pairs in x[t..n); between(t): across.
  std::vector<double> within_left(n + 1, 0.0), within_right(n + 1, 0.0);
  for (std::size_t t = 1; t <= n; ++t) within_left[t] = within_left[t - 1] + to_left[t - 1];
  for (std::size_t t = n; t-- > 0;) within_right[t] = within_right[t + 1] + to_right[t];
  double between = 0;  // t = 0: nothing on the left
  for (std::size_t t = 1; t < n; ++t) {
    // x_{t-1} moves from the right side to the left.
    between += to_right[t - 1] - to_left[t - 1];
    const double m = static_cast<double>(t), k = static_cast<double>(n - t);
    if (t < min_size || n - t < min_size) continue;
    const double e = 2.0 * between / (m * k) - within_left[t] / (m * (m - 1) / 2) - within_right[t] / (k * (k - 1) / 2);
    q[t] = m * k / (m + k) * e;
  }
  return q;
}

std::vector<ChangePoint> e_divisive(const std::vector<double>& values, const ChangePointOptions& o) {
  if (o.permutations < 1 || o.min_segment < 2 || !(o.max_p_value > 0 && o.max_p_value < 1))
    throw std::invalid_argument("e_divisive: permutations >= 1, min_segment >= 2 and 0 < max_p_value < 1");
  std::vector<double> x;
  for (double v : values) {
    if (!(v > 0) || !std::isfinite(v)) throw std::invalid_argument("e_divisive: values must be positive and finite");
    x.push_back(std::log(v));
  }
  std::mt19937_64 rng(o.seed);
  std::vector<std::size_t> cuts = {0, x.size()};  // segment boundaries
  std::vector<ChangePoint> found;
  for (;;) {
    // The best split of any segment.
    Best best;
    std::size_t seg_begin = 0, seg_end = 0;
    for (std::size_t s = 0; s + 1 < cuts.size(); ++s) {
      const std::vector<double> seg(x.begin() + cuts[s], x.begin() + cuts[s + 1]);
      const Best b = best_split(seg, o.min_segment);
      if (b.q > best.q) best = {cuts[s] + b.tau, b.q}, seg_begin = cuts[s], seg_end = cuts[s + 1];
    }
    if (best.q <= 0) break;
    // Its significance: how often a random order of the same values splits as well.
    std::vector<double> seg(x.begin() + seg_begin, x.begin() + seg_end);
    int as_good = 0;
    for (int r = 0; r < o.permutations; ++r) {
      std::shuffle(seg.begin(), seg.end(), rng);
      if (best_split(seg, o.min_segment).q >= best.q) ++as_good;
    }
    const double p = (as_good + 1.0) / (o.permutations + 1.0);
    if (p > o.max_p_value) break;
    found.push_back({best.tau, 1.0, p, best.q});
    cuts.insert(std::upper_bound(cuts.begin(), cuts.end(), best.tau), best.tau);
  }
  std::sort(found.begin(), found.end(), [](const ChangePoint& a, const ChangePoint& b) { return a.index < b.index; });
  // Each step's size against its neighbouring segments.
  for (std::size_t c = 0; c < found.size(); ++c) {
    const std::size_t from = c == 0 ? 0 : found[c - 1].index;
    const std::size_t to = c + 1 < found.size() ? found[c + 1].index : values.size();
    const double before = median_of({values.begin() + from, values.begin() + found[c].index});
    const double after = median_of({values.begin() + found[c].index, values.begin() + to});
    found[c].ratio = before > 0 ? after / before : 1;
  }
  return found;
}

}  // namespace bokeh::history
