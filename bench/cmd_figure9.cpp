// `bokehbench figure9`: FLAG paper Figure 9, frame time vs gather size for each method, on the
// Vulkan device and as CPU references, measured interleaved, with spread, fitted growth exponents
// and the naive/FLAG ratio.
#include <fmt/format.h>

#include "commands.hpp"
#include "method.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "stats.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct Figure9Options {
  AxisFlags axes;
  SweepFlags sweep;
  MethodOptionFlags method_options;
};

nlohmann::json fit_json(const PowerLawFit& f) {
  return {{"exponent", f.exponent}, {"coefficient_ms", f.coefficient}, {"r_squared", f.r_squared}, {"points", f.points}};
}

// Per method and backend: the points in N order, the exponent of frame time vs N over all sizes and
// over the larger half (where fixed costs such as the CoC pass no longer dominate), and the median
// relative IQR of its points.
nlohmann::json series_json(const nlohmann::json& points) {
  // In registry order, GPU first.
  std::vector<std::pair<std::pair<std::string, std::string>, std::vector<const nlohmann::json*>>> groups;
  for (const Method& m : registered_methods())
    for (const char* backend : {"gpu", "cpu"}) {
      std::vector<const nlohmann::json*> pts;
      for (const auto& p : points)
        if (p["method"] == m.name && p["backend"] == backend) pts.push_back(&p);
      if (!pts.empty()) groups.push_back({{m.name, backend}, pts});
    }
  nlohmann::json out = nlohmann::json::array();
  for (auto& [key, pts] : groups) {
    std::sort(pts.begin(), pts.end(), [](auto* a, auto* b) { return (*a)["N"] < (*b)["N"]; });
    std::vector<double> n, ms, iqr;
    for (const auto* p : pts) {
      n.push_back((*p)["N"].get<double>());
      ms.push_back((*p)["frame_ms"]["median"].get<double>());
      iqr.push_back((*p)["relative_iqr"].get<double>());
    }
    nlohmann::json fits = nlohmann::json::object();
    if (n.size() >= 2) fits["all_sizes"] = fit_json(fit_power_law(n, ms));
    const std::size_t half = n.size() / 2;
    if (n.size() - half >= 2)
      fits["larger_half"] = fit_json(fit_power_law({n.begin() + half, n.end()}, {ms.begin() + half, ms.end()}));
    std::sort(iqr.begin(), iqr.end());
    out.push_back({{"method", key.first},
                   {"backend", key.second},
                   {"N", n},
                   {"median_ms", ms},
                   {"median_relative_iqr", iqr.empty() ? 0.0 : iqr[iqr.size() / 2]},
                   {"fits", fits}});
  }
  return out;
}

// The paper's headline: naive over FLAG at each N, per backend (both at their default precision).
nlohmann::json ratios_json(const nlohmann::json& points) {
  nlohmann::json ratios = nlohmann::json::array();
  for (const auto& a : points) {
    if (a["method"] != "naive") continue;
    for (const auto& b : points)
      if (b["method"] == "flag" && b["backend"] == a["backend"] && b["N"] == a["N"] && b["buffer_scale"] == 1)
        ratios.push_back({{"N", a["N"]},
                          {"backend", a["backend"]},
                          {"naive_over_flag", a["frame_ms"]["median"].get<double>() / b["frame_ms"]["median"].get<double>()}});
  }
  return ratios;
}

void figure9(Figure9Options& o) {
  o.axes.resolve(&o.sweep);
  if (o.axes.methods.empty()) o.axes.methods = default_sweep_methods();
  Axes axes;
  axes.methods = o.axes.methods;
  axes.backends = o.axes.backends;
  axes.scenes = o.axes.scenes;
  axes.resolutions = o.axes.frame_sizes();
  axes.patterns = o.axes.patterns();
  axes.precisions = o.axes.precisions;
  axes.option_values = o.method_options.values_for(axes.methods);
  std::vector<int> sizes;
  for (const auto& p : axes.patterns) sizes.push_back(p.size_n);

  SweepSettings s = o.sweep.settings("figure9", "plot_figure9.py");
  s.config = {{"scene", axes.scenes.front()},
              {"width_px", axes.resolutions.front().width_px},
              {"height_px", axes.resolutions.front().height_px},
              {"spacing_px", o.axes.spacing_px},
              {"sizes", sizes},
              {"patterns", o.axes.sizes},
              {"methods", axes.methods},
              {"backends", axes.backends},
              {"precisions", axes.precisions},
              {"quick", o.axes.quick},
              {"scene_coc", "lens f-stop set per N so the scene's largest CoC radius equals the pattern's max radius"},
              {"error", "each point's output against the exact scatter references (energy_sum: the plain sum naive and "
                        "FLAG approximate; depth_ordered: composited front to back) of the same scene and CoC"}};
  s.derive = [](nlohmann::json& doc) {
    doc["series"] = series_json(doc["points"]);
    doc["naive_over_flag"] = ratios_json(doc["points"]);
  };
  s.summary = [](const nlohmann::json& doc) {
    fmt::print("\n{:<12} {:<4} {:>9} {:>9} {:>14}\n", "method", "on", "~N^b", "(all N)", "median rel IQR");
    for (const auto& series : doc["series"]) {
      const auto& f = series["fits"];
      auto exponent = [&](const char* which) {
        return f.contains(which) ? fmt::format("{:.2f}", f[which]["exponent"].get<double>()) : std::string("-");
      };
      fmt::print("{:<12} {:<4} {:>9} {:>9} {:>13.1f}%\n", series["method"].get<std::string>(),
                 series["backend"].get<std::string>(), exponent("larger_half"), exponent("all_sizes"),
                 100 * series["median_relative_iqr"].get<double>());
    }
    for (const auto& r : doc["naive_over_flag"])
      fmt::print("naive / FLAG at N={} ({}): {:.2f}x\n", r["N"].get<int>(), r["backend"].get<std::string>(),
                 r["naive_over_flag"].get<double>());
  };
  run_sweep(expand(axes), s);
}

}  // namespace

void add_figure9_command(CLI::App& app) {
  auto o = std::make_shared<Figure9Options>();
  auto* cmd = app.add_subcommand("figure9", "Reproduce FLAG paper Figure 9: frame time vs gather size");
  AxisFlags& a = o->axes;
  a.sizes = {"5", "9", "13", "17", "21", "25", "29", "33", "37", "41"};  // at k = 2, as the paper
  a.resolutions = {"800x600"};
  a.scenes = {"hoops"};
  a.backends = {"gpu", "cpu"};
  a.add_to(cmd, {Axis::sizes, Axis::methods, Axis::backends, Axis::precisions}, {Axis::resolutions, Axis::scenes});
  o->method_options.add_to(cmd);
  o->sweep.add_to(cmd, 300);
  a.add_quick(cmd, "Small sweep for CI and tests (200x150, N = 5, 9, 13, 20 s)",
              {{Axis::sizes, {"5", "9", "13"}}, {Axis::resolutions, {"200x150"}}}, 20);
  cmd->callback([o] { figure9(*o); });
}

}  // namespace bokeh
