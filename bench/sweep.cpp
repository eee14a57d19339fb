#include "sweep.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <iostream>
#include <stdexcept>

#include <fmt/format.h>

#include "report.hpp"

namespace bokeh {

namespace {

std::atomic<bool> g_interrupted{false};

extern "C" void on_sigint(int) {
  if (g_interrupted.exchange(true)) std::_Exit(130);  // a second Ctrl-C stops at once
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - lo);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

// Collects a point's runs; forwards them to gbench's JSONReporter only once the point is accepted.
class Sweep::Reporter : public benchmark::BenchmarkReporter {
 public:
  explicit Reporter(std::ostream& file) { json_.SetOutputStream(&file), json_.SetErrorStream(&std::cerr); }
  bool ReportContext(const Context& context) override {
    if (!context_written_) json_.ReportContext(context), context_written_ = true;
    return true;
  }
  void ReportRuns(const std::vector<Run>& runs) override { runs_.insert(runs_.end(), runs.begin(), runs.end()); }

  std::vector<Run> take() { return std::exchange(runs_, {}); }
  // gbench names a run .../iterations:I/repetitions:R, but a point's I and R come from its pilot frame
  // and change between runs; without them the names are stable, so compare.py can pair two runs.
  // Both counts stay in the JSON as their own keys.
  void accept(std::vector<Run> runs) {
    for (Run& run : runs) run.run_name.iterations.clear(), run.run_name.repetitions.clear();
    json_.ReportRuns(runs);
  }
  void finish() {
    if (context_written_) json_.Finalize();
  }

 private:
  benchmark::JSONReporter json_;
  std::vector<Run> runs_;
  bool context_written_ = false;
};

Sweep::Sweep(const std::string& gbench_json_path, RepetitionPolicy policy) : policy_(policy) {
  ensure_parent_dir(gbench_json_path);
  gbench_file_.open(gbench_json_path);
  if (!gbench_file_) throw std::runtime_error(fmt::format("cannot write '{}'", gbench_json_path));
  reporter_ = std::make_unique<Reporter>(gbench_file_);
  static bool initialized = false;
  if (!initialized) {
    // gbench keeps argv[0] as the executable name for its JSON context: it must outlive the run.
    static char name[] = "bokehbench";
    static char* argv[] = {name, nullptr};
    int argc = 1;
    benchmark::Initialize(&argc, argv);
    initialized = true;
  }
  g_interrupted = false;
  std::signal(SIGINT, on_sigint);
}

Sweep::~Sweep() {
  reporter_->finish();
  std::signal(SIGINT, SIG_DFL);
}

bool Sweep::interrupted() { return g_interrupted; }

nlohmann::json distribution_json(const Distribution& d) {
  return {{"median", d.median}, {"q1", d.q1}, {"q3", d.q3},         {"min", d.min},
          {"max", d.max},       {"mean", d.mean}, {"stddev", d.stddev}};
}

PointStats Sweep::measure(const std::string& name, const std::function<void()>& warm_up, const FrameFn& frame,
                          bool gpu) {
  const auto start = std::chrono::steady_clock::now();
  warm_up();
  const auto pilot_start = std::chrono::steady_clock::now();
  const auto pilot_passes = frame();
  const double pilot_ms = gpu ? vk::frame_ms(pilot_passes) : seconds_since(pilot_start) * 1e3;

  const long iterations = std::clamp<long>(static_cast<long>(std::ceil(policy_.repetition_min_ms / pilot_ms)), 1, 50);
  const double repetition_s = iterations * pilot_ms * 1e-3;
  int repetitions = std::clamp(static_cast<int>(policy_.point_budget_s / repetition_s), policy_.min_repetitions,
                               policy_.max_repetitions);

  PointStats stats;
  std::vector<benchmark::BenchmarkReporter::Run> runs;
  for (;;) {
    benchmark::ClearRegisteredBenchmarks();
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [&](benchmark::State& state) {
      std::map<std::string, double> pass_sums;
      for (auto _ : state) {
        const auto passes = frame();
        if (gpu) state.SetIterationTime(vk::frame_ms(passes) * 1e-3);
        for (const auto& p : passes) pass_sums[p.pass] += p.ms;
      }
      for (const auto& [pass, sum] : pass_sums)
        state.counters[pass + "_ms"] = benchmark::Counter(sum, benchmark::Counter::kAvgIterations);
    });
    b->Unit(benchmark::kMillisecond)->Iterations(iterations)->Repetitions(repetitions);
    if (gpu) b->UseManualTime(); else b->UseRealTime();
    b->ComputeStatistics("min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); })
        ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); })
        ->ComputeStatistics("q1", [](const std::vector<double>& v) { return quantile(v, 0.25); })
        ->ComputeStatistics("q3", [](const std::vector<double>& v) { return quantile(v, 0.75); });
    benchmark::RunSpecifiedBenchmarks(reporter_.get());
    runs = reporter_->take();

    std::vector<double> frame_ms;
    std::map<std::string, std::vector<double>> pass_ms;
    for (const auto& run : runs) {
      if (run.error_occurred) throw std::runtime_error(fmt::format("{}: {}", name, run.error_message));
      if (run.run_type != benchmark::BenchmarkReporter::Run::RT_Iteration) continue;
      frame_ms.push_back(run.GetAdjustedRealTime());
      for (const auto& [counter, value] : run.counters) pass_ms[counter.substr(0, counter.size() - 3)].push_back(value);
    }
    double sum = 0, sq = 0;
    for (double v : frame_ms) sum += v, sq += v * v;
    const double mean = sum / frame_ms.size();
    stats.frame_ms = {quantile(frame_ms, 0.5), quantile(frame_ms, 0.25), quantile(frame_ms, 0.75),
                      *std::min_element(frame_ms.begin(), frame_ms.end()),
                      *std::max_element(frame_ms.begin(), frame_ms.end()), mean,
                      std::sqrt(std::max(0.0, sq / frame_ms.size() - mean * mean))};
    stats.pass_ms.clear();
    for (const auto& [pass, values] : pass_ms) stats.pass_ms[pass] = quantile(values, 0.5);
    stats.repetitions = repetitions;
    stats.iterations_per_repetition = iterations;

    // Not settled yet: one more round with the most repetitions, if that fits twice the budget.
    const bool settled = stats.frame_ms.relative_iqr() <= policy_.settled_relative_iqr;
    const double another_round_s = policy_.max_repetitions * repetition_s;
    if (settled || repetitions >= policy_.max_repetitions || interrupted() ||
        seconds_since(start) + another_round_s > 2 * policy_.point_budget_s)
      break;
    repetitions = policy_.max_repetitions;
  }
  reporter_->accept(runs);
  stats.wall_s = seconds_since(start);
  return stats;
}

}  // namespace bokeh
