#pragma once
// One sweep runner for every command: a command declares its axes and what to write; this takes
// their product, skips impossible or over-budget points with the reason, measures the rest
// interleaved (runner.hpp) on the GPU and as CPU references, attaches each point's error against the
// cached exact reference, writes partial results atomically beside the complete ones, and plots.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "method.hpp"
#include "runner.hpp"
#include "scene.hpp"

namespace bokeh {

struct Resolution {
  int width_px = 800, height_px = 600;
  std::string text() const;
};
// "WIDTHxHEIGHT", 16..16384 px a side; throws std::invalid_argument naming the text.
Resolution parse_resolution(const std::string& text);
// "NxK", a valid gather pattern; throws std::invalid_argument naming the text.
GatherPattern parse_pattern(const std::string& text);

// "42 s", or "3m05s" from 90 s on: durations and ETAs in progress lines.
std::string duration_text(double seconds);

// A sweep's axes: the product of all of them, less what a method does not accept.
struct Axes {
  std::vector<std::string> methods;
  std::vector<std::string> backends = {"gpu"};
  std::vector<std::string> scenes = {"hoops"};
  std::vector<Resolution> resolutions = {Resolution{}};
  std::vector<GatherPattern> patterns;
  // Precisions: empty = each method's default; {"all"} = every one a method accepts; otherwise those
  // listed (a method that accepts none of them runs at its default).
  std::vector<std::string> precisions;
  // Buffer scales: empty = 1; {0} = every scale a method accepts; otherwise those listed.
  std::vector<int> scales;
  // Method options set on the command line (applied to the methods that have them).
  std::map<std::string, double> option_values;
  // Also sweep each option's `tradeoff` values (tradeoff).
  bool sweep_options = false;
  // Options (by key) swept over every one of their choices where a method has them as an
  // enumeration and option_values does not fix them (adaptive: off and on).
  std::vector<std::string> sweep_choices;
  // The scene's largest CoC radius: empty = the pattern's max radius (the lens follows N, as in
  // figure9), else each of these many px (an axis, outermost).
  std::vector<double> max_coc_px;  // a point id names it (/coc:R) when it differs from the pattern's
  // The lens's aperture (issue 23): empty = the disc; a point id names any other (/aperture:blades6).
  // Methods that cannot draw one are skipped with their reason (Method::aperture_unsupported).
  std::vector<Aperture> apertures;
  // This process measures shard `shard_index` (1-based) of `shard_count`: expand() keeps that share of
  // the points (shard_of), so a scheduler runs one sweep over several machines.
  int shard_index = 1, shard_count = 1;
};

// "i/n" with 1 <= i <= n (--shard, --process); throws std::invalid_argument naming the flag and the text.
std::pair<int, int> parse_shard(const std::string& text, const std::string& flag = "--shard");
// --shard auto or auto/N: the shard ("i/n") from the scheduler's index, so one command line serves
// Slurm and Kubernetes. Slurm array task: SLURM_ARRAY_TASK_ID less SLURM_ARRAY_TASK_MIN (1 when unset)
// plus 1, of SLURM_ARRAY_TASK_COUNT (or MAX - MIN + 1); a stepped or sparse array is refused.
// Kubernetes indexed Job: JOB_COMPLETION_INDEX (0-based) plus 1, of N (the Job's completions: Kubernetes
// gives no count). A given N must equal Slurm's count. Throws std::invalid_argument naming what it
// looked for when it finds no index, or an index that is not a shard of N. `env` reads a variable
// (nullptr when unset); when not given, std::getenv.
std::string resolve_auto_shard(const std::string& text, const std::function<const char*(const char*)>& env = nullptr);
// What a shard's run records as context.sweep_id (store.hpp, sweep_identity_of): BOKEH_SWEEP_ID when
// set (a Kubernetes Job's uid, by the manifest), else "slurm:" + SLURM_ARRAY_JOB_ID, else "".
std::string scheduler_sweep_id(const std::function<const char*(const char*)>& env = nullptr);
// What stays together in one shard: a point's id less its method and variant, so the points a
// command compares with each other (naive and FLAG at one N, adaptive off and on) are measured on
// one machine, in the same rounds, and no ratio mixes two machines.
std::string shard_key(const std::string& id, const std::string& method, const std::string& variant);

struct SweepPoint {
  std::string id;  // stable across runs: what results and Google Benchmark names carry
  std::string variant;  // the method's options off their defaults, "/key:value" each (the id ends with it)
  const Method* method = nullptr;
  std::string backend;
  std::string scene;
  Resolution resolution;
  FilterOptions options;
  double max_coc_px = 0;
};

std::vector<SweepPoint> expand(const Axes& axes);
// What the points that run on the GPU need of a device, all together (nullopt: none runs there).
std::optional<vk::DeviceRequirements> gpu_requirements(const std::vector<SweepPoint>& points);

struct SweepSettings {
  std::string name;  // results/<name>.json, results/<name>_gbench.json, plots/<name>.png
  std::string out_dir = "results", plots_dir = "plots", plot_script, reference_cache = "build/reference-cache";
  std::string device;
  runner::Policy policy;
  double max_buffer_mb = 0;  // > 0: points whose intermediates exceed this many MiB are skipped unallocated
  // > 0: points whose one frame is estimated above this many seconds are skipped (SweepTargets; the
  // commands set it to --budget-s unless --run-over-budget).
  double frame_budget_s = 0;
  int cpu_threads = 0;       // 0: every core
  // A GPU submission running past this + 20x its warm-up's estimate is stopped as a runaway: that
  // point is skipped naming the pass, and the GPU points after it too (the device cannot be
  // stopped); 0: no watchdog.
  double watchdog_s = 60;
  bool plot = true;
  // Answer a paired comparison's requests on stdin instead of running the rounds (paired.hpp).
  bool serve = false;
  nlohmann::json config = nlohmann::json::object();  // the command's own settings, recorded as they are
  // The shard this run measures (recorded in config.shard as "i/n" when shard_count > 1).
  int shard_index = 1, shard_count = 1;
  // > 1: the run is measured by this many processes one after another (processes.hpp), each this same
  // command line with --process k/P (process_index k, 0 in the run that joins them).
  int processes = 1, process_index = 0;
  // Process k > 1 of several: the run's out_dir, where the processes before it wrote their results
  // (processes::part_dir); its points_needed reads their rounds followed by its own.
  std::string run_out_dir;
  // The results store the run is appended to (store.hpp); empty: none.
  std::string store_url;
  // A further reference for some points (e.g. full-resolution f32 FLAG for `buffers`): the point's
  // error gains vs_<field>; make() runs once per distinct key.
  struct ExtraReference {
    std::string field, key;
    std::function<Image()> make;
  };
  std::function<std::optional<ExtraReference>(const SweepPoint&, const Scene&, const Lens&)> extra_reference;
  // Points visited back to back in every round (runner::Hooks::visit_group): those whose keys are
  // equal. Empty: every point on its own.
  std::function<std::string(const SweepPoint&)> visit_together;
  // Groups visited one after another in every round (runner::Hooks::visit_block): those whose points'
  // keys are equal. Empty: every group on its own.
  std::function<std::string(const SweepPoint&)> visit_block;
  // Which points a figure still too wide needs (runner::Hooks::points_needed), given the run's
  // context (its device): one flag per point, then one per baseline; empty: all of them.
  std::function<std::vector<bool>(const runner::RunRecord&, const nlohmann::json& context)> points_needed;
  // Timed things that are no method (figure9's CPU baseline, cpu_baseline.hpp): measured in the same
  // rounds as the points (the runner's points after them, visited with the points whose keys they share),
  // written to the document's "baselines" (measured) and "skipped_baselines", never given an error, a
  // work model or a place among the methods' points, so no accuracy ranking, comparison or store series
  // reads them as a method.
  struct Baseline {
    std::string id;            // stable across runs, as a point's id
    nlohmann::json identity;   // what names it in results (id included)
    std::string scene;         // whose colour it filters, at `resolution`
    Resolution resolution;
    std::string skip;          // why it cannot run in this build ("" when it can)
    std::string visit_together, visit_block;  // its keys among the points' (visit_together(p), visit_block(p))
    std::function<std::unique_ptr<runner::Target>(const Scene& scene)> prepare;
  };
  std::vector<Baseline> baselines;
  // Adds the command's derived results (fits, ratios, Pareto front) to the document.
  std::function<void(nlohmann::json& doc)> derive;
  // Prints the command's summary from the finished document.
  std::function<void(const nlohmann::json& doc)> summary;
};

// Each calibration probe's drift over the run's rounds ((max - min) / median), by name, from a sweep
// document's `measurement`; and as text: "cpu_copy 79%, gpu_copy 119%" ("" when none was measured).
nlohmann::json probe_drift(const nlohmann::json& measurement);
std::string probe_drift_text(const nlohmann::json& drift);

// Runs the sweep and returns the document written to <out_dir>/<name>.json (with status
// "complete"), or, interrupted, to <name>.partial.json beside any earlier complete result (and then
// throws, naming the file).
nlohmann::json run_sweep(const std::vector<SweepPoint>& points, const SweepSettings& settings);

}  // namespace bokeh
