#pragma once
// Change points of a series over commits by E-divisive means (Matteson & James, "A nonparametric
// approach for multiple change point analysis of multivariate data", JASA 2014), the method Apache
// Otava (Hunter) and MongoDB's performance CI use. Why this and not a fixed threshold: it compares the
// whole distribution before and after a candidate split (energy distance), so it needs no noise model,
// copes with a noisy machine, and finds several steps in one history; a permutation test gives each
// step a p-value, so "confidence" is a measured quantity, not a tuned threshold.
//
// Binary segmentation: the split that maximises the energy statistic Q over all current segments is
// tested by permuting that segment's values; while it is significant it is kept and its two halves are
// searched again. Values are taken as logs, so a step is a ratio (+5% is the same step at 1 ms or 1 s).
#include <cstdint>
#include <vector>

namespace bokeh::history {

struct ChangePointOptions {
  double max_p_value = 0.01;  // a split is kept when its permutation p-value is at most this
  int permutations = 999;     // p-values are multiples of 1 / (permutations + 1)
  int min_segment = 3;        // values on each side of a split, at least
  std::uint64_t seed = 1;     // of the permutations (results are reproducible)
};

struct ChangePoint {
  std::size_t index = 0;  // the first value after the step
  double ratio = 1;       // median after / median before, over the neighbouring segments
  double p_value = 1;
  double q = 0;           // the energy statistic of the split
};

// The change points of `values` (positive: times), in index order.
std::vector<ChangePoint> e_divisive(const std::vector<double>& values, const ChangePointOptions& options = {});

// The energy statistic Q(tau) of splitting x at every tau (x[0..tau) | x[tau..n)); 0 where a side has
// fewer than min_segment values. O(n^2).
std::vector<double> energy_statistics(const std::vector<double>& x, int min_segment);

}  // namespace bokeh::history
