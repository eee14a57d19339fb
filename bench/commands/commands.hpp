#pragma once
// Each bokehbench subcommand registers itself on the CLI11 app; main() only dispatches.
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "aperture.hpp"

namespace bokeh {

struct SweepSettings;
struct GatherPattern;
struct Resolution;
struct SweepFlags;
struct Axes;
namespace compare {
struct Report;
}

// Every registered method's own options as flags of a command (--near-components, ...), kept as
// given; values_for() parses them for the chosen methods.
class MethodOptionFlags {
 public:
  void add_to(CLI::App* cmd);
  // key -> value for the options given; throws std::invalid_argument naming a flag that none of
  // `methods` has, or a value the method refuses.
  std::map<std::string, double> values_for(const std::vector<std::string>& methods) const;

 private:
  std::map<std::string, std::string> given_;
};

// The axes, spelled alike in every command (the spellings before them stay as aliases for a release):
//   -N, --sizes       gather sizes N, or NxK with a spacing of its own    (--gather, --pattern, --patterns)
//   -k, --spacing     the spacing of sizes given as N
//   --resolutions     frame sizes WxH (--width / --height change one)
//   --precisions  (--precision)   --scales  (--scale, --buffer-scale)
//   --scenes  (--scene)           --methods  (--method)        --backends  (--backend)
// A command adds the axes it has: `lists` take one value or more, `single` ones exactly one (render
// makes one image; figure9 draws one frame size). --quick gives each axis its quick value unless the
// axis was given on the command line.
enum class Axis { sizes, resolutions, precisions, scales, scenes, methods, backends, apertures };

struct AxisFlags {
  std::vector<std::string> sizes, resolutions, precisions, scenes, methods, backends;  // as given or defaulted
  std::vector<std::string> apertures = {"disc"};  // Aperture::name()s
  std::vector<int> scales;
  int spacing_px = 2;
  bool quick = false;

  void add_to(CLI::App* cmd, const std::vector<Axis>& lists, const std::vector<Axis>& single);
  // Adds --quick: each axis in `values` takes its quick value (sizes and resolutions as text) unless
  // given; so does the budget (--budget-s) of `sweep` when quick_budget_s > 0.
  void add_quick(CLI::App* cmd, const std::string& help, std::map<Axis, std::vector<std::string>> values,
                 double quick_budget_s = 0);
  // After parsing: applies --quick, --width/--height, and checks the single axes have one value;
  // throws std::invalid_argument naming the flag.
  void resolve(SweepFlags* sweep = nullptr);
  bool given(Axis axis) const;
  CLI::Option* option(Axis axis) const { return options_.at(axis); }

  std::vector<GatherPattern> patterns() const;  // validated
  std::vector<Resolution> frame_sizes() const;  // validated
  std::vector<Aperture> aperture_shapes() const;  // validated

 private:
  std::map<Axis, CLI::Option*> options_;
  std::map<Axis, std::vector<std::string>> quick_values_;
  double quick_budget_s_ = 0;
  std::vector<Axis> single_;
  CLI::Option *width_ = nullptr, *height_ = nullptr;
  int width_px_ = 0, height_px_ = 0;
};

// What every sweep command takes: budget, device, output folders, memory budget, seed.
struct SweepFlags {
  double budget_s = 0;
  std::string device, out_dir = "results", reference_cache = "build/reference-cache";
  std::string plots_dir;  // --plots-dir; empty: plots/ beside the default --out-dir, else that --out-dir
  int cpu_threads = 0;
  double max_buffer_mb = 0;
  double sample_ms = 60;     // --sample-ms: runner::Policy::sample_min_ms
  double lead_in_ms = -1;    // --lead-in-ms: runner::Policy::lead_in_ms; < 0: auto (run_sweep)
  unsigned seed = 1;
  int inject_slowdown_pct = 0;  // a test of `compare` only (selftest-compare); 0: off
  bool plot = true;
  bool serve = false;  // a worker of `bokehbench ab` (paired.hpp)
  double watchdog_s = 60;        // --watchdog-s: SweepSettings::watchdog_s
  bool run_over_budget = false;  // run points whose one frame is estimated above the budget
  std::string shard = "1/1";     // --shard i/n (parse_shard)
  std::string store;             // --store URL; empty: <out_dir>/history.sqlite
  bool no_store = false;         // --no-store: append nothing
  int processes = 1;             // --processes P (processes.hpp)
  int replicas = 1;              // --replicas R (runner::Policy::replicas)
  std::string process;           // --process k/P: this is process k of such a run (internal)
  CLI::Option* processes_option = nullptr;
  // The shard as axes take it (call after parsing; throws std::invalid_argument naming --shard).
  void apply_shard(Axes& axes) const;
  CLI::Option* budget_option = nullptr;
  void add_to(CLI::App* cmd, double default_budget_s, double default_max_buffer_mb = 0);
  SweepSettings settings(const std::string& name, const std::string& plot_script) const;
};

// The methods a command sweeps when none are named: every registered method that is not kept out
// of default sweeps.
std::vector<std::string> default_sweep_methods();

// Thrown by a command whose outcome is an exit status other than 0 without being an error
// (compare: 2 = regression, 3 = not comparable, 4 = work changed); main() returns `code`.
struct ExitStatus {
  int code = 0;
};

// Refuses NaN and infinities in a number option: CLI11's Range and PositiveNumber let NaN through
// (every comparison with NaN is false). Every floating-point option of every command checks it.
const CLI::Validator& finite_number();
// --threshold-pct and --confidence, alike in compare and ab.
void add_verdict_flags(CLI::App* cmd, double& threshold_pct, double& confidence);
// Prints a comparison's verdicts (and writes them as JSON when json_out is set); throws ExitStatus
// with the report's exit code when it is not 0 (compare and ab).
void report_verdicts(const compare::Report& report, const std::string& json_out);

// True when the user gave `option` on the command line (so --quick must not override it).
inline bool given(const CLI::Option* option) { return option->count() > 0; }

// FLAG through its 3D buffer (layer_buffer = full) unless the command line chose where its layers go:
// adaptive and buffers measure the buffer, which auto leaves out on CPU devices (layers in registers).
void flag_through_its_buffer(Axes& axes);

// A sweep's derived figures (ratios, fits, speed-ups, fronts) from its document's points and config,
// the code its command runs: `merge` recomputes them over the merged shards' points with these.
void derive_figure9(nlohmann::json& doc);
void derive_adaptive(nlohmann::json& doc);
void derive_tradeoff(nlohmann::json& doc);
void derive_buffers(nlohmann::json& doc);

void add_devices_command(CLI::App& app);
void add_methods_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_memory_command(CLI::App& app);
void add_buffers_command(CLI::App& app);
void add_figure9_command(CLI::App& app);
void add_kernels_command(CLI::App& app);
void add_tradeoff_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_selftest_compare_command(CLI::App& app);
void add_ab_command(CLI::App& app);
void add_stability_command(CLI::App& app);
void add_adaptive_command(CLI::App& app);
void add_history_command(CLI::App& app);
void add_report_command(CLI::App& app);
void add_merge_command(CLI::App& app);
void add_check_command(CLI::App& app);

}  // namespace bokeh
