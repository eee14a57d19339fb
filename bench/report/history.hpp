#pragma once
// A point's history as series over commits, one per machine (runs on different machines are never
// one statistic), with its change points (changepoints.hpp).
#include <string>
#include <vector>

#include "changepoints.hpp"
#include "store.hpp"

namespace bokeh::history {

enum class Metric { wall, cpu };  // frame_ms (wall clock per frame) or cpu_ms (process CPU time per frame)
Metric parse_metric(const std::string& text);  // "wall" or "cpu"; throws std::invalid_argument
const char* metric_name(Metric metric);

// One commit's value: the median over its runs' samples pooled, with their quartiles. A headline
// figure's: the median of its runs' values, and of their intervals' ends (q1_ms, q3_ms) when every run
// gave one (has_interval), else the values' quartiles.
// A commit's runs (of one method package's version, where the point is a package's: an edit of the
// package is a new value at the same commit).
struct CommitValue {
  std::string commit, date_utc;  // date: of its first run
  std::string package;           // the package's content hash ("": a built-in method)
  double median_ms = 0, q1_ms = 0, q3_ms = 0;
  int runs = 0, samples = 0;
  bool has_interval = false;
};

struct Step {
  std::string commit;         // the first commit after the step
  std::string before_commit;  // the last commit before it
  std::size_t index = 0;      // into Series::values
  double ratio = 1, p_value = 1;
};

struct Series {
  std::string point_id, sweep, machine;  // point_id: a point's id, or a headline figure's name
  std::string unit = "ms";               // a headline figure's: ratio, exponent, cases
  bool headline = false;
  std::vector<CommitValue> values;  // in commit order (each commit at its first run's date)
  std::vector<Step> steps;
};

// Commits in the order they were first measured; a commit's runs pooled.
std::vector<CommitValue> over_commits(const std::vector<SeriesValue>& runs, Metric metric);
// Every series of `point_id` (one per machine), or of every point and headline figure when it is empty;
// with change points. `point_id` may name a headline figure (Store::headline_names); `metric` applies
// to points (a headline figure is the figure its run derived).
std::vector<Series> series(Store& store, const std::string& point_id, Metric metric, const ChangePointOptions& options);

}  // namespace bokeh::history
