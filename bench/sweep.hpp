#pragma once
// Measures one configuration ("point") at a time through Google Benchmark: it owns the timing
// loop, repetitions and statistics; we pick how many repetitions a point gets and tee gbench's own
// JSONReporter to a file so its compare tooling works on our runs.
#include <atomic>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "vk/timestamps.hpp"

namespace bokeh {

// One frame of work. GPU frames return their timestamped passes (the frame time is their sum);
// CPU frames return nothing and are timed by gbench's wall clock.
using FrameFn = std::function<std::vector<vk::PassTime>()>;

struct Distribution {
  double median = 0, q1 = 0, q3 = 0, min = 0, max = 0, mean = 0, stddev = 0;
  double relative_iqr() const { return median > 0 ? (q3 - q1) / median : 0; }
};
// {median, q1, q3, min, max, mean, stddev}: how every results file reports a timing.
nlohmann::json distribution_json(const Distribution& d);

struct PointStats {
  Distribution frame_ms;                  // over repetitions, each the mean of its iterations
  std::map<std::string, double> pass_ms;  // median over repetitions, GPU only
  int repetitions = 0;
  long iterations_per_repetition = 0;
  double wall_s = 0;  // what measuring the point cost, pilot included
};

struct RepetitionPolicy {
  double point_budget_s = 6;      // aim for this much measuring per point...
  int min_repetitions = 3;        // ...but never fewer repetitions than this (slow points overrun)
  int max_repetitions = 15;
  double repetition_min_ms = 60;  // a repetition runs enough frames to last at least this long
  double settled_relative_iqr = 0.05;  // more repetitions only while IQR / median exceeds this
};

class Sweep {
 public:
  // gbench_json_path: Google Benchmark's JSON output for every finished point.
  Sweep(const std::string& gbench_json_path, RepetitionPolicy policy);
  ~Sweep();

  // Warms up, takes a pilot frame, chooses repetitions and iterations, then runs gbench.
  // `warm_up` runs before the pilot (JIT compilation on lavapipe).
  PointStats measure(const std::string& name, const std::function<void()>& warm_up, const FrameFn& frame, bool gpu);

  // Set by SIGINT: the caller finishes the current point, writes what it has, and stops.
  static bool interrupted();

 private:
  class Reporter;
  RepetitionPolicy policy_;
  std::ofstream gbench_file_;
  std::unique_ptr<Reporter> reporter_;
};

}  // namespace bokeh
