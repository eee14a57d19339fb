// `bokehbench compare BASELINE CURRENT`: per point a verdict (same / faster / slower /
// inconclusive) with the ratio of medians and its interval; the exit status is what a CI job acts
// on (see bench/report/compare.hpp for the statistic and the codes).
#include <fmt/format.h>

#include "commands.hpp"
#include "compare.hpp"
#include "report.hpp"

namespace bokeh {

namespace {

struct CompareOptions {
  std::string baseline, current, json_out;
  double threshold_pct = 10, confidence = 0.95;
  int min_samples = 5;
  std::string normalise = "auto", times = "auto";
};

void run_compare(const CompareOptions& o) {
  compare::Options options;
  options.rule.threshold = o.threshold_pct / 100;
  options.rule.confidence = o.confidence;
  options.rule.min_samples = o.min_samples;
  options.normalise = o.normalise;
  options.times = o.times;
  if (!o.json_out.empty()) check_writable_file(o.json_out, {o.baseline, o.current});
  const nlohmann::json baseline = compare::load_results(o.baseline), current = compare::load_results(o.current);
  const compare::Report report = compare::compare_results(baseline, current, options, o.baseline, o.current);
  report_verdicts(report, o.json_out);
}

}  // namespace

void report_verdicts(const compare::Report& report, const std::string& json_out) {
  // The file first: if it cannot be written, the run fails before its last line states an exit status.
  if (!json_out.empty())
    write_results(json_out, "bokehbench.compare", run_context(nullptr), compare::report_json(report));
  fmt::print("{}", compare::report_text(report));
  if (!json_out.empty()) fmt::print("wrote {}\n", json_out);
  if (report.exit_code() != compare::kNoRegression) throw ExitStatus{report.exit_code()};
}

void add_compare_command(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  auto* cmd = app.add_subcommand(
      "compare",
      "Compare two sweep results files point by point. Exit status: 0 no confident regression, 1 error (unreadable or "
      "malformed file; bad arguments: CLI11's codes from 100), 2 a point confidently slower by more than the threshold, 3 files not comparable (schema, "
      "device, methods or points differ), 4 work counters changed (algorithmic change) without a timing regression");
  cmd->add_option("baseline", o->baseline, "Results file to compare against (a figure9 --json or sweep JSON file)")
      ->required();
  cmd->add_option("current", o->current, "Results file of the run under test")->required();
  add_verdict_flags(cmd, o->threshold_pct, o->confidence);
  cmd->add_option("--min-samples", o->min_samples, "Fewer samples than this on a side: inconclusive")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  cmd->add_option("--normalise", o->normalise,
                  "auto: divide each sample by its backend's calibration probes of the same round (copy and FMA); "
                  "none: raw times; or probe names, comma-separated (e.g. gpu_copy)")
      ->capture_default_str();
  cmd->add_option("--times", o->times,
                  "auto: the process CPU time per frame where the device is the CPU (lavapipe; other processes on "
                  "the machine do not inflate it), else the timestamps; wall: timestamps / wall clock; cpu: CPU time")
      ->check(CLI::IsMember({"auto", "wall", "cpu"}))
      ->capture_default_str();
  cmd->add_option("--json", o->json_out, "Also write the comparison as JSON here");
  cmd->callback([o] { run_compare(*o); });
}

}  // namespace bokeh
