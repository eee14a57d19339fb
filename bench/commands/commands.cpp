#include "commands.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "method.hpp"
#include "processes.hpp"
#include "scene.hpp"
#include "store.hpp"
#include "sweep.hpp"

namespace bokeh {

void MethodOptionFlags::add_to(CLI::App* cmd) {
  // An option several methods share (adaptive) is one flag; its help gathers each distinct meaning.
  std::vector<std::pair<const OptionSpec*, std::string>> flags;  // the first spec of each key, the help
  for (const Method* m : known_methods())
    for (const OptionSpec& spec : m->options) {
      auto it = std::find_if(flags.begin(), flags.end(), [&](const auto& f) { return f.first->key == spec.key; });
      if (it == flags.end())
        flags.emplace_back(&spec, spec.help);
      else if (it->second.find(spec.help) == std::string::npos)
        it->second += " | " + spec.help;
    }
  for (const auto& [spec, help] : flags)
    cmd->add_option_function<std::string>(
        spec->flag(), [this, key = spec->key](const std::string& text) { given_[key] = text; }, help);
}

std::map<std::string, double> MethodOptionFlags::values_for(const std::vector<std::string>& methods) const {
  std::map<std::string, double> values;
  for (const auto& [key, text] : given_) {
    const OptionSpec* spec = nullptr;
    for (const auto& name : methods)
      if ((spec = find_method(name).option(key))) break;
    if (!spec) {
      std::string owners;
      for (const Method* m : known_methods())
        if (m->option(key)) owners += (owners.empty() ? "" : ", ") + m->name;
      std::string flag = "--" + key;
      std::replace(flag.begin(), flag.end(), '_', '-');
      throw std::invalid_argument(fmt::format("{} applies to {}, none of the methods chosen ({})", flag, owners,
                                              fmt::join(methods, ", ")));
    }
    values[key] = spec->parse(text);
  }
  return values;
}

namespace {

struct AxisSpelling {
  const char* names;  // the canonical name first, then the aliases
  const char* one;    // help when the command takes one value
  const char* many;   // help when it takes a list
};

AxisSpelling spelling(Axis axis) {
  switch (axis) {
    case Axis::sizes:
      return {"-N,--sizes,--gather,--pattern,--patterns", "Gather size N (odd), or NxK with its own spacing",
              "Gather sizes N (odd), or NxK with a spacing of their own"};
    case Axis::resolutions:
      return {"--resolutions", "Frame size WIDTHxHEIGHT", "Frame sizes WIDTHxHEIGHT"};
    case Axis::precisions:
      return {"--precisions,--precision", "Storage of the intermediates, e.g. FLAG layers f16 (default: the method's)",
              "Storages of the intermediates, e.g. FLAG layers f16 f32 (default: each method's own; all: every one)"};
    case Axis::scales:
      return {"--scales,--scale,--buffer-scale", "Resolution divisor of the intermediates (FLAG: 1, 2 or 4)",
              "Resolution divisors of the intermediates (FLAG: 1 full, 2 half, 4 quarter)"};
    case Axis::scenes:
      return {"--scenes,--scene", "Procedural scene", "Procedural scenes"};
    case Axis::methods:
      return {"--methods,--method", "Filter method (`bokehbench methods` lists them)",
              "Methods (default: every method in the default sweeps)"};
    case Axis::backends:
      return {"--backends,--backend", "gpu (Vulkan) or cpu (reference)", "gpu and/or cpu"};
    case Axis::apertures:
      return {"--apertures,--aperture",
              "Lens aperture: disc, or blades<N>[-rot<degrees>][-curv<0..1>] (N = 5..9; rotation 0: a vertex up; "
              "curvature 1: the disc), e.g. blades6",
              "Lens apertures (an axis; methods that cannot draw one are skipped with the reason): disc, or "
              "blades<N>[-rot<degrees>][-curv<0..1>] (N = 5..9; rotation 0: a vertex up), e.g. disc blades6 blades5"};
  }
  throw std::logic_error("unknown axis");
}

}  // namespace

void AxisFlags::add_to(CLI::App* cmd, const std::vector<Axis>& lists, const std::vector<Axis>& single) {
  single_ = single;
  std::vector<Axis> all = lists;
  all.insert(all.end(), single.begin(), single.end());
  for (Axis axis : all) {
    const AxisSpelling s = spelling(axis);
    const bool one = std::find(single.begin(), single.end(), axis) != single.end();
    const std::string help = one ? s.one : s.many;
    CLI::Option* opt = nullptr;
    switch (axis) {
      case Axis::sizes: opt = cmd->add_option(s.names, sizes, help); break;
      case Axis::resolutions: opt = cmd->add_option(s.names, resolutions, help); break;
      case Axis::precisions: opt = cmd->add_option(s.names, precisions, help); break;
      case Axis::scales: opt = cmd->add_option(s.names, scales, help); break;
      case Axis::scenes:
        opt = cmd->add_option(s.names, scenes, help)->check(CLI::IsMember(procedural_scene_names()));
        break;
      case Axis::methods: opt = cmd->add_option(s.names, methods, help); break;
      case Axis::backends: opt = cmd->add_option(s.names, backends, help)->check(CLI::IsMember({"gpu", "cpu"})); break;
      case Axis::apertures: opt = cmd->add_option(s.names, apertures, help); break;
    }
    opt->capture_default_str();
    options_[axis] = opt;
    if (axis == Axis::sizes) cmd->add_option("-k,--spacing", spacing_px, "Sample spacing k in px of sizes given as N")
                                 ->check(CLI::Range(1, 1024))
                                 ->capture_default_str();
    if (axis == Axis::resolutions && one) {
      width_ = cmd->add_option("--width", width_px_, "Frame width in px (with the height of --resolutions)")
                   ->check(CLI::Range(16, 16384));
      height_ = cmd->add_option("--height", height_px_, "Frame height in px (with the width of --resolutions)")
                    ->check(CLI::Range(16, 16384));
    }
  }
}

void AxisFlags::add_quick(CLI::App* cmd, const std::string& help, std::map<Axis, std::vector<std::string>> values,
                          double quick_budget_s) {
  quick_values_ = std::move(values);
  quick_budget_s_ = quick_budget_s;
  cmd->add_flag("--quick", quick, help);
}

void flag_through_its_buffer(Axes& axes) {
  const OptionSpec* layer_buffer = find_method("flag").option("layer_buffer");
  if (!axes.option_values.count(layer_buffer->key)) axes.option_values[layer_buffer->key] = layer_buffer->parse("full");
}

bool AxisFlags::given(Axis axis) const {
  const auto it = options_.find(axis);
  return it != options_.end() && it->second->count() > 0;
}

void AxisFlags::resolve(SweepFlags* sweep) {
  if (quick) {
    for (const auto& [axis, values] : quick_values_) {
      if (given(axis)) continue;
      if (axis == Axis::sizes) sizes = values;
      if (axis == Axis::resolutions) resolutions = values;
      if (axis == Axis::scenes) scenes = values;
      if (axis == Axis::methods) methods = values;
      if (axis == Axis::precisions) precisions = values;
    }
    if (sweep && quick_budget_s_ > 0 && !bokeh::given(sweep->budget_option)) sweep->budget_s = quick_budget_s_;
  }
  if ((width_ && width_->count()) || (height_ && height_->count())) {
    Resolution r = resolutions.empty() ? Resolution{} : parse_resolution(resolutions.front());
    if (width_->count()) r.width_px = width_px_;
    if (height_->count()) r.height_px = height_px_;
    resolutions = {r.text()};
  }
  auto refuse_repeats = [](const char* flag, auto values) {
    std::sort(values.begin(), values.end());
    if (const auto it = std::adjacent_find(values.begin(), values.end()); it != values.end())
      throw std::invalid_argument(fmt::format("{} {} is given twice", flag, *it));
  };
  refuse_repeats("--sizes", sizes);
  refuse_repeats("--resolutions", resolutions);
  refuse_repeats("--precisions", precisions);
  refuse_repeats("--scales", scales);
  refuse_repeats("--scenes", scenes);
  refuse_repeats("--methods", methods);
  refuse_repeats("--backends", backends);
  refuse_repeats("--apertures", apertures);
  for (Axis axis : single_) {
    std::size_t count = 0;
    switch (axis) {
      case Axis::sizes: count = sizes.size(); break;
      case Axis::resolutions: count = resolutions.size(); break;
      case Axis::precisions: count = precisions.size() > 1 ? 2 : 1; break;  // empty: the method's default
      case Axis::scales: count = scales.size() > 1 ? 2 : 1; break;
      case Axis::scenes: count = scenes.size(); break;
      case Axis::methods: count = methods.size(); break;
      case Axis::backends: count = backends.size(); break;
      case Axis::apertures: count = apertures.size(); break;
    }
    if (count != 1) {
      const std::string names = spelling(axis).names;
      const std::string name = names.substr(names.find("--"), names.find(',', names.find("--")) - names.find("--"));
      throw std::invalid_argument(fmt::format("{}: this command takes one value, not {}", name, count));
    }
  }
  frame_sizes();  // the errors name the text now, before any work
  patterns();
  aperture_shapes();
}

std::vector<Aperture> AxisFlags::aperture_shapes() const {
  std::vector<Aperture> out;
  for (const auto& text : apertures) {
    try {
      out.push_back(parse_aperture(text));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("--apertures: {}", e.what()));
    }
  }
  return out;
}

std::vector<GatherPattern> AxisFlags::patterns() const {
  std::vector<GatherPattern> out;
  for (const auto& text : sizes) {
    const bool plain_n = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!plain_n && text.find('x') == std::string::npos)
      throw std::invalid_argument(fmt::format("--sizes '{}' is not a gather size N or a pattern NxK", text));
    out.push_back(parse_pattern(plain_n ? fmt::format("{}x{}", text, spacing_px) : text));  // validated
  }
  return out;
}

std::vector<Resolution> AxisFlags::frame_sizes() const {
  std::vector<Resolution> out;
  for (const auto& text : resolutions) out.push_back(parse_resolution(text));
  return out;
}

const CLI::Validator& finite_number() {
  static const CLI::Validator validator(
      [](std::string& text) -> std::string {
        double value = 0;
        try {
          value = std::stod(text);
        } catch (const std::exception&) {
          return "'" + text + "' is not a number";
        }
        return std::isfinite(value) ? std::string() : "'" + text + "' is not a finite number";
      },
      "FINITE");
  return validator;
}

void add_verdict_flags(CLI::App* cmd, double& threshold_pct, double& confidence) {
  cmd->add_option("--threshold-pct", threshold_pct,
                  "Smallest change that counts, in percent: slower only when the whole interval lies above it")
      ->check(finite_number())
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  cmd->add_option("--confidence", confidence, "Confidence of each point's interval")
      ->check(finite_number())
      ->check(CLI::Range(0.5, 0.9999))
      ->capture_default_str();
}

void SweepFlags::add_to(CLI::App* cmd, double default_budget_s, double default_max_buffer_mb) {
  budget_s = default_budget_s;
  max_buffer_mb = default_max_buffer_mb;
  budget_option = cmd->add_option("--budget-s", budget_s, "Measuring time to aim for, all points together (each still gets "
                                          "its minimum samples)")
      ->check(finite_number())
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--max-buffer-mb", max_buffer_mb,
                  "Skip (never allocate) points whose intermediates exceed this many MiB (0: no limit)")
      ->check(finite_number())
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--cpu-threads", cpu_threads, "Threads for the CPU references (default: every core)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--sample-ms", sample_ms,
                  "Each visit takes one sample of frames enough to last this long (a frame longer than it: one frame)")
      ->check(finite_number())
      ->check(CLI::Range(1.0, 10000.0))
      ->capture_default_str();
  cmd->add_option("--lead-in-ms", lead_in_ms,
                  "Untimed frames worth this long before each sample, to warm the device's state (default: a quarter "
                  "sample on GPUs, whose clocks fall while other points run; none on CPU devices such as lavapipe)")
      ->check(finite_number())
      ->check(CLI::Range(0.0, 10000.0));
  cmd->add_flag("--run-over-budget", run_over_budget,
                "Run points whose single frame is estimated to take longer than --budget-s (by default they are "
                "skipped before anything runs, with the estimate: their taps at a ceiling rate)");
  cmd->add_option("--watchdog-s", watchdog_s,
                  "A GPU submission running longer than this plus 20x its estimate (the warm-up's corner scaled to "
                  "the frame) is a runaway: its point is skipped naming the pass, and so are the GPU points after it, "
                  "since the device cannot be stopped (0: wait as long as it takes)")
      ->check(finite_number())
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--device", device, "Vulkan device index or name part (default: a GPU if present, else lavapipe)");
  cmd->add_option("--seed", seed, "Seed of the shuffled measuring order")->capture_default_str();
  cmd->add_option("--out-dir", out_dir, "Where the results files go")->capture_default_str();
  cmd->add_option("--plots-dir", plots_dir,
                  "Where the plots go (default: plots/, or the --out-dir when one is given, so that a run kept "
                  "elsewhere leaves plots/ as it is)");
  cmd->add_option("--reference-cache", reference_cache, "Directory caching the exact references")->capture_default_str();
  cmd->add_flag("!--no-plot", plot, "Skip the plot");
  cmd->add_option("--inject-slowdown-pct", inject_slowdown_pct,
                  "Test of `compare` only: every sample runs this many percent more frames than it reports, a known "
                  "slowdown of every point (recorded in the results' config)")
      ->check(CLI::Range(0, 100));
  cmd->add_option("--shard", shard,
                  "Measure shard i of n (1-based, e.g. 2/3): a share of the points, the points a command compares "
                  "kept together; run every shard (each its own machine or process) and join them with "
                  "`bokehbench merge` or read them from one --store. auto: the scheduler's index, one line for "
                  "every task: a Slurm array task (SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN + 1 of "
                  "SLURM_ARRAY_TASK_COUNT); auto/N: N shards, for a Kubernetes indexed Job (JOB_COMPLETION_INDEX + 1 "
                  "of N, N = its completions; Kubernetes gives no count) or a Slurm array of N tasks. Refused, "
                  "before anything runs, where no index is set. The results' config.shard is the resolved i/n; a "
                  "shard's context.sweep_id names its job (BOKEH_SWEEP_ID, else Slurm's SLURM_ARRAY_JOB_ID), and a "
                  "store given the same shard of one job twice keeps the second as 'duplicate', counted nowhere")
      ->transform(CLI::Validator(
          [](std::string& text) {
            if (text.rfind("auto", 0) != 0) return std::string();  // i/n: parse_shard checks it
            try {
              text = resolve_auto_shard(text);
              return std::string();
            } catch (const std::invalid_argument& e) {
              return std::string(e.what());
            }
          },
          "", "shard"))
      ->capture_default_str();
  cmd->add_option("--store", store,
                  "Results store the run is appended to: a file (SQLite) or postgresql://user@host/db (default: "
                  "OUT_DIR/history.sqlite)");
  cmd->add_flag("--no-store", no_store, "Append the run to no results store");
  processes_option = cmd->add_option("--processes", processes,
                                     "Measure in this many processes one after another, each for the budget's share, "
                                     "their rounds joined: figures then carry the spread between processes, which "
                                     "one process's rounds cannot show (results/README.md, \"Do two runs agree?\")")
                         ->check(CLI::Range(1, 16))
                         ->capture_default_str();
  cmd->add_option("--replicas", replicas,
                  "Prepare each point this many times (each with allocations of its own), its visits taking them in "
                  "turn: on machines where memory placement is a draw, a point's samples then span that many draws "
                  "(results/README.md, \"Do two runs agree?\"); costs that many times the intermediates' memory")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  // Internal: how a run of several processes starts each of them (processes.hpp).
  cmd->add_option("--process", process, "Internal (--processes): this is process k of P")->group("");
  // Internal: how `bokehbench ab` starts the two builds it compares (answers on stdin, not for people).
  cmd->add_flag("--serve", serve, "Internal (bokehbench ab): time samples on request over stdin/stdout")->group("");
}

SweepSettings SweepFlags::settings(const std::string& name, const std::string& plot_script) const {
  SweepSettings s;
  s.name = name;
  s.plot_script = plot_script;
  s.out_dir = out_dir;
  s.plots_dir = !plots_dir.empty() ? plots_dir : out_dir == "results" ? "plots" : out_dir;
  s.reference_cache = reference_cache;
  s.device = device;
  s.cpu_threads = cpu_threads;
  s.max_buffer_mb = max_buffer_mb;
  s.frame_budget_s = run_over_budget ? 0.0 : budget_s;
  s.watchdog_s = watchdog_s;
  s.plot = plot;
  s.policy.budget_s = budget_s;
  s.policy.sample_min_ms = sample_ms;
  s.policy.lead_in_ms = lead_in_ms;
  s.policy.seed = seed;
  s.policy.replicas = replicas;
  s.policy.extra_work_fraction = inject_slowdown_pct / 100.0;
  s.serve = serve;
  const auto [index, count] = parse_shard(shard);
  s.shard_index = index;
  s.shard_count = count;
  // A worker of `ab` writes nothing; tests of `compare` (injected slowdowns) are not history.
  if (!no_store && !serve && inject_slowdown_pct == 0) s.store_url = store.empty() ? history::default_store_url(out_dir) : store;
  s.processes = serve ? 1 : processes;  // a worker of `ab` is one process by its nature
  if (!process.empty()) {  // process k of P: its share of the budget and its own order, into its own folder only
    const auto [k, count] = parse_shard(process, "--process");
    s.process_index = k;
    s.processes = 1;
    s.policy.budget_s = budget_s / count;
    s.policy.seed = seed + static_cast<unsigned>(k - 1);
    s.out_dir = processes::part_dir(out_dir, name, k);
    s.run_out_dir = out_dir;
    s.plot = false;
    s.store_url.clear();
  }
  return s;
}

void SweepFlags::apply_shard(Axes& axes) const {
  const auto [index, count] = parse_shard(shard);
  if (serve && count > 1) throw std::invalid_argument("--shard: a worker of `ab` measures every point");
  axes.shard_index = index;
  axes.shard_count = count;
}

std::vector<std::string> default_sweep_methods() {
  std::vector<std::string> names;
  for (const Method& m : registered_methods())
    if (m.in_default_sweeps) names.push_back(m.name);
  return names;
}

}  // namespace bokeh
