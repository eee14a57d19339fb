#include "commands.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "method.hpp"
#include "sweep.hpp"

namespace bokeh {

void MethodOptionFlags::add_to(CLI::App* cmd) {
  // An option several methods share (adaptive) is one flag; its help gathers each distinct meaning.
  std::vector<std::pair<const OptionSpec*, std::string>> flags;  // the first spec of each key, the help
  for (const Method& m : registered_methods())
    for (const OptionSpec& spec : m.options) {
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
      for (const Method& m : registered_methods())
        if (m.option(key)) owners += (owners.empty() ? "" : ", ") + m.name;
      std::string flag = "--" + key;
      std::replace(flag.begin(), flag.end(), '_', '-');
      throw std::invalid_argument(fmt::format("{} applies to {}, none of the methods chosen ({})", flag, owners,
                                              fmt::join(methods, ", ")));
    }
    values[key] = spec->parse(text);
  }
  return values;
}

void SweepFlags::add_to(CLI::App* cmd, double default_budget_s, double default_max_buffer_mb) {
  budget_s = default_budget_s;
  max_buffer_mb = default_max_buffer_mb;
  cmd->add_option("--budget-s", budget_s, "Measuring time to aim for, all points together (each still gets "
                                          "its minimum samples)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--max-buffer-mb", max_buffer_mb,
                  "Skip (never allocate) points whose intermediates exceed this many MiB (0: no limit)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--cpu-threads", cpu_threads, "Threads for the CPU references (default: every core)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--device", device, "Vulkan device index or name part (default: a GPU if present, else lavapipe)");
  cmd->add_option("--seed", seed, "Seed of the shuffled measuring order")->capture_default_str();
  cmd->add_option("--out-dir", out_dir, "Where the results files go")->capture_default_str();
  cmd->add_option("--plots-dir", plots_dir, "Where the plots go")->capture_default_str();
  cmd->add_option("--reference-cache", reference_cache, "Directory caching the exact references")->capture_default_str();
  cmd->add_flag("!--no-plot", plot, "Skip the plot");
  cmd->add_option("--inject-slowdown-pct", inject_slowdown_pct,
                  "Test of `compare` only: every sample runs this many percent more frames than it reports, a known "
                  "slowdown of every point (recorded in the results' config)")
      ->check(CLI::Range(0, 100));
  // Internal: how `bokehbench ab` starts the two builds it compares (answers on stdin, not for people).
  cmd->add_flag("--serve", serve, "Internal (bokehbench ab): time samples on request over stdin/stdout")->group("");
}

SweepSettings SweepFlags::settings(const std::string& name, const std::string& plot_script) const {
  SweepSettings s;
  s.name = name;
  s.plot_script = plot_script;
  s.out_dir = out_dir;
  s.plots_dir = plots_dir;
  s.reference_cache = reference_cache;
  s.device = device;
  s.cpu_threads = cpu_threads;
  s.max_buffer_mb = max_buffer_mb;
  s.plot = plot;
  s.policy.budget_s = budget_s;
  s.policy.seed = seed;
  s.policy.extra_work_fraction = inject_slowdown_pct / 100.0;
  s.serve = serve;
  return s;
}

std::vector<std::string> default_sweep_methods() {
  std::vector<std::string> names;
  for (const Method& m : registered_methods())
    if (m.in_default_sweeps) names.push_back(m.name);
  return names;
}

}  // namespace bokeh
