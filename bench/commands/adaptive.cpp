// `bokehbench adaptive`: what modelling only what a scene requires buys. Every registered method that
// declares the option `adaptive` (off: sized for the worst case; on: only what the scene needs) is
// measured both ways, interleaved, on scenes from mostly in focus to fully defocused, each at one or
// more largest CoC radii below or at the pattern's: per scene and method, the speed-up, the memory
// allocated and saved (what the filter allocated for the scene, not the model), and the error of
// each mode against the exact scatter.
#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "accuracy.hpp"
#include "commands.hpp"
#include "intervals.hpp"
#include "method.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

constexpr const char* kOption = "adaptive";  // the option's key, the same in every method that has it

struct AdaptiveOptions {
  AxisFlags axes;
  std::vector<double> max_coc_px = {12, 40};
  SweepFlags sweep;
  MethodOptionFlags method_options;
  CLI::Option* coc_opt = nullptr;
};

// Every registered method that declares the adaptive option as an enumeration with "off" and "on".
std::vector<std::string> adaptive_methods() {
  std::vector<std::string> names;
  for (const Method& m : registered_methods())
    if (const OptionSpec* spec = m.option(kOption)) {
      const auto& c = spec->choices;
      if (std::find(c.begin(), c.end(), "off") != c.end() && std::find(c.begin(), c.end(), "on") != c.end())
        names.push_back(m.name);
    }
  return names;
}

double median_ms(const nlohmann::json& point) { return point["frame_ms"]["median"].get<double>(); }

// off / on of the samples the two points took side by side in the same round: the machine's drift
// (a shared VM moves by 2x within minutes) cancels in each ratio. Their median with its 95% interval
// (the order statistics of the rounds, intervals.hpp) and their quartiles.
nlohmann::json paired_speedup(const nlohmann::json& off, const nlohmann::json& on) {
  const RoundValues off_ms = round_values(off), on_ms = round_values(on);
  const auto ratio = paired_ratio_interval(off_ms, on_ms);
  if (!ratio) return nullptr;
  std::vector<double> ratios;
  for (const auto& [round, ms] : on_ms)
    if (auto it = off_ms.find(round); it != off_ms.end() && ms > 0) ratios.push_back(it->second / ms);
  return {{"median", ratio->estimate}, {"low", ratio->low}, {"high", ratio->high},
          {"q1", runner::quantile(ratios, 0.25)}, {"q3", runner::quantile(ratios, 0.75)}, {"rounds", ratios.size()}};
}

nlohmann::json error_summary(const nlohmann::json& point) {
  const auto& e = point["error"]["vs_energy_sum"];
  return {{"psnr_db", e["psnr_db"]}, {"rmse", e["rmse"]}, {"max_abs_error", e["max_abs_error"]}};
}

// Pairs each adaptive = on point with its off twin (everything else equal).
nlohmann::json comparisons_json(const nlohmann::json& points) {
  auto key = [](const nlohmann::json& p) {
    nlohmann::json options = p["options"];
    options.erase(kOption);
    return fmt::format("{}|{}|{}x{}|{}x{}|{}|{}|{}|{}", p["method"].get<std::string>(), p["scene"].get<std::string>(),
                       p["width_px"].get<int>(), p["height_px"].get<int>(), p["N"].get<int>(), p["k"].get<int>(),
                       p["precision"].get<std::string>(), p["buffer_scale"].get<int>(), p["max_coc_px"].get<double>(),
                       options.dump());
  };
  std::map<std::string, const nlohmann::json*> off;
  for (const auto& p : points)
    if (p["options"].value(kOption, "") == "off") off[key(p)] = &p;
  nlohmann::json out = nlohmann::json::array();
  for (const auto& on : points) {
    if (on["options"].value(kOption, "") != "on") continue;
    const auto it = off.find(key(on));
    if (it == off.end()) continue;
    const nlohmann::json& w = *it->second;
    const auto bytes = [](const nlohmann::json& p) {
      return p["memory"].value("allocated_bytes", p["memory"]["bytes"].get<std::uint64_t>());
    };
    const std::uint64_t off_bytes = bytes(w), on_bytes = bytes(on);
    nlohmann::json c = {
        {"method", on["method"]},
        {"scene", on["scene"]},
        {"max_coc_px", on["max_coc_px"]},
        {"max_radius_px", on["max_radius_px"]},
        {"precision", on["precision"]},
        {"off_id", w["id"]},
        {"on_id", on["id"]},
        {"frame_ms_off", median_ms(w)},
        {"frame_ms_on", median_ms(on)},
        {"speedup", median_ms(on) > 0 ? median_ms(w) / median_ms(on) : 0.0},
        {"speedup_same_round", paired_speedup(w, on)},
        {"allocated_bytes_off", off_bytes},
        {"allocated_bytes_on", on_bytes},
        {"memory_saved_bytes", static_cast<double>(off_bytes) - static_cast<double>(on_bytes)},
        {"memory_saved_fraction",
         off_bytes > 0 ? nlohmann::json(1.0 - static_cast<double>(on_bytes) / static_cast<double>(off_bytes))
                       : nlohmann::json(nullptr)},
        {"error_off", error_summary(w)},
        {"error_on", error_summary(on)},
        {"scene_stats", on["stats"].value(kOption, nlohmann::json::object())}};
    out.push_back(std::move(c));
  }
  return out;
}

std::string mib_text(double bytes) {
  if (std::abs(bytes) < 1024 * 1024) return fmt::format("{:.1f} KiB", bytes / 1024);
  return fmt::format("{:.2f} MiB", bytes / (1024 * 1024));
}

void adaptive(AdaptiveOptions& o) {
  o.axes.resolve(&o.sweep);
  if (o.axes.quick && !given(o.coc_opt)) o.max_coc_px = {4};
  std::vector<std::string>& methods = o.axes.methods;
  const std::vector<std::string> candidates = adaptive_methods();
  if (methods.empty())
    for (const auto& name : candidates)
      if (find_method(name).in_default_sweeps) methods.push_back(name);
  for (const auto& name : methods) {
    find_method(name);  // unknown names: the registry's message
    if (std::find(candidates.begin(), candidates.end(), name) == candidates.end())
      throw std::invalid_argument(fmt::format("method '{}' has no option '{}' (methods with one: {})", name, kOption,
                                              fmt::join(candidates, ", ")));
  }
  if (methods.empty()) throw std::invalid_argument("no registered method declares the option 'adaptive'");
  Axes axes;
  axes.methods = methods;
  axes.backends = {"gpu"};
  axes.scenes = o.axes.scenes;
  axes.resolutions = o.axes.frame_sizes();
  axes.patterns = o.axes.patterns();
  axes.option_values = o.method_options.values_for(methods);
  if (axes.option_values.count(kOption))
    throw std::invalid_argument("--adaptive: this command measures every method both ways; leave it out");
  axes.sweep_choices = {kOption};
  // FLAG both ways through the same 3D buffer: auto runs none (registers) on lavapipe where adaptive
  // cannot, which would compare two designs instead of the scene's bound.
  flag_through_its_buffer(axes);
  axes.max_coc_px = o.max_coc_px;
  o.sweep.apply_shard(axes);
  const std::vector<SweepPoint> points = expand(axes);

  SweepSettings s = o.sweep.settings("adaptive", "plot_adaptive.py");
  s.config = {{"scenes", axes.scenes},
              {"max_coc_px", o.max_coc_px},
              {"pattern", fmt::format("{}x{}", axes.patterns.front().size_n, axes.patterns.front().spacing_px)},
              {"width_px", axes.resolutions.front().width_px},
              {"height_px", axes.resolutions.front().height_px},
              {"methods", methods},
              {"backend", "gpu"},
              {"quick", o.axes.quick},
              {"worst_case", "adaptive = off: every method sized for the pattern's largest radius"},
              {"speedup", "median frame time off / on (frames include the CoC pass and, on, the tile-map passes)"},
              {"memory", "memory.allocated_bytes: what the filter allocated once prepared for the scene"},
              {"error", "each mode against the exact energy-sum scatter of the same scene and CoC"}};
  // Off and on of one configuration side by side in every round: their speed-up is paired.
  s.visit_together = [](const SweepPoint& p) {
    FilterOptions o = p.options;
    o.values.erase(kOption);
    return fmt::format("{}/{}/{}/{}/{}", p.method->name, p.scene, p.resolution.text(), p.max_coc_px, o.precision) +
           nlohmann::json(o.values).dump();
  };
  s.derive = derive_adaptive;
  s.summary = [](const nlohmann::json& doc) {
    fmt::print("\n{:<18} {:>7} {:<8} {:>9} {:>9} {:>8} {:>17} {:>12} {:>12} {:>8} {:>10} {:>10}\n", "scene",
               "max CoC", "method", "off ms", "on ms", "speed-up", "(paired, 95%)", "off alloc", "on alloc", "saved",
               "PSNR off", "PSNR on");
    for (const auto& c : doc["comparisons"]) {
      const auto& saved = c["memory_saved_fraction"];
      const auto& paired = c["speedup_same_round"];
      const std::string same_round =
          paired.is_null() ? std::string("-")
                           : fmt::format("{:.2f}x [{:.2f}-{:.2f}]", paired["median"].get<double>(),
                                         paired["low"].get<double>(), paired["high"].get<double>());
      fmt::print("{:<18} {:>5.0f}px {:<8} {:>9.2f} {:>9.2f} {:>7.2f}x {:>17} {:>12} {:>12} {:>8} {:>10} {:>10}\n",
                 c["scene"].get<std::string>(), c["max_coc_px"].get<double>(), c["method"].get<std::string>(),
                 c["frame_ms_off"].get<double>(), c["frame_ms_on"].get<double>(), c["speedup"].get<double>(), same_round,
                 mib_text(c["allocated_bytes_off"].get<double>()), mib_text(c["allocated_bytes_on"].get<double>()),
                 saved.is_null() ? std::string("-") : fmt::format("{:.0f}%", 100 * saved.get<double>()),
                 psnr_text(c["error_off"]), psnr_text(c["error_on"]));
    }
  };
  run_sweep(points, s);
}

}  // namespace

void derive_adaptive(nlohmann::json& doc) { doc["comparisons"] = comparisons_json(doc["points"]); }

void add_adaptive_command(CLI::App& app) {
  auto o = std::make_shared<AdaptiveOptions>();
  auto* cmd = app.add_subcommand(
      "adaptive", "Worst-case vs adaptive (model only what the scene requires): speed-up, memory, error per scene");
  AxisFlags& a = o->axes;
  a.scenes = {"mostly_in_focus", "half_defocused", "fully_defocused"};
  a.sizes = {"41x2"};  // the pattern the filters are provisioned for
  a.resolutions = {"800x600"};
  a.add_to(cmd, {Axis::scenes, Axis::methods}, {Axis::sizes, Axis::resolutions});
  o->coc_opt = cmd->add_option("--max-coc", o->max_coc_px,
                               "The scenes' largest CoC radius in px, each measured at every value (sets the f-stop; "
                               "below the pattern's largest radius, the worst case provisions more than needed)")
                   ->check(finite_number());
  o->method_options.add_to(cmd);
  o->sweep.add_to(cmd, 240);
  a.add_quick(cmd, "Small run for CI and tests (160x120, pattern 9x2, max CoC 4 px, 8 s)",
              {{Axis::resolutions, {"160x120"}}, {Axis::sizes, {"9x2"}}}, 8);
  cmd->callback([o] { adaptive(*o); });
}

}  // namespace bokeh
