// `bokehbench tradeoff`: time per frame against error for every configuration of every method on one
// scene (precisions, buffer scales, patterns and each method's own speed/quality options), measured
// interleaved, with the Pareto front (fastest for its accuracy) drawn and listed.
#include <fmt/format.h>

#include "accuracy.hpp"
#include "commands.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "stats.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct TradeoffOptions {
  std::string scene = "hoops", backend = "gpu";
  int width_px = 800, height_px = 600;
  double max_coc_px = 40;
  // Gather patterns as NxK; each covers max_coc_px when k (N - 1) / 2 equals it.
  std::vector<std::string> patterns = {"41x2", "21x4", "11x8"};
  std::vector<std::string> methods;
  SweepFlags sweep;
  MethodOptionFlags method_options;
  bool quick = false;
  CLI::Option *width_opt = nullptr, *height_opt = nullptr, *coc_opt = nullptr, *patterns_opt = nullptr,
              *budget_opt = nullptr;
};

// Configurations nothing beats on both median time and PSNR (exact = +inf), fastest first. PSNRs
// within 0.1 dB count as the same accuracy (e.g. FLAG f16 vs f32 on the same pattern): no one can
// see that difference, so it should not buy a slower configuration a place on the front.
nlohmann::json pareto_ids(const nlohmann::json& points) {
  std::vector<double> time_ms, psnr_db;
  for (const auto& c : points) {
    time_ms.push_back(c["frame_ms"]["median"].get<double>());
    psnr_db.push_back(psnr_for_ranking(c["error"]["vs_energy_sum"]));
  }
  nlohmann::json front = nlohmann::json::array();
  for (std::size_t i : pareto_front(time_ms, psnr_db, 0.1)) front.push_back(points[i]["id"]);
  return front;
}

void tradeoff(TradeoffOptions& o) {
  if (o.quick) {
    if (!given(o.width_opt)) o.width_px = 160;
    if (!given(o.height_opt)) o.height_px = 120;
    if (!given(o.coc_opt)) o.max_coc_px = 8;
    if (!given(o.patterns_opt)) o.patterns = {"9x2", "5x4"};
    if (!given(o.budget_opt)) o.sweep.budget_s = 15;
  }
  if (o.methods.empty()) o.methods = default_sweep_methods();
  Axes axes;
  axes.methods = o.methods;
  axes.backends = {o.backend};
  axes.scenes = {o.scene};
  axes.resolutions = {{o.width_px, o.height_px}};
  for (const auto& p : o.patterns) axes.patterns.push_back(parse_pattern(p));
  axes.precisions = {"all"};
  axes.scales = {0};
  axes.option_values = o.method_options.values_for(o.methods);
  axes.sweep_options = true;
  axes.max_coc_px = o.max_coc_px;

  SweepSettings s = o.sweep.settings("tradeoff", "plot_tradeoff.py");
  s.config = {{"scene", o.scene},       {"width_px", o.width_px},   {"height_px", o.height_px},
              {"max_coc_px", o.max_coc_px}, {"backend", o.backend}, {"patterns", o.patterns},
              {"methods", o.methods},
              {"pareto", "minimise frame_ms median, maximise PSNR vs the energy_sum exact reference"}};
  s.derive = [](nlohmann::json& doc) { doc["pareto_front"] = pareto_ids(doc["points"]); };
  s.summary = [](const nlohmann::json& doc) {
    fmt::print("\nPareto front (fastest first: nothing is both faster and more accurate):\n");
    for (const auto& id : doc["pareto_front"])
      for (const auto& c : doc["points"])
        if (c["id"] == id)
          fmt::print("  for {:9.2f} ms you can have at best {:>9}  ({})\n", c["frame_ms"]["median"].get<double>(),
                     psnr_text(c["error"]["vs_energy_sum"]), id.get<std::string>());
  };
  run_sweep(expand(axes), s);
}

}  // namespace

void add_tradeoff_command(CLI::App& app) {
  auto o = std::make_shared<TradeoffOptions>();
  auto* cmd = app.add_subcommand("tradeoff", "Time vs error for every configuration, with the Pareto front");
  cmd->add_option("--scene", o->scene, "Procedural scene")->check(CLI::IsMember(procedural_scene_names()));
  o->width_opt = cmd->add_option("--width", o->width_px, "Image width in px")->check(CLI::Range(16, 16384));
  o->height_opt = cmd->add_option("--height", o->height_px, "Image height in px")->check(CLI::Range(16, 16384));
  o->coc_opt = cmd->add_option("--max-coc", o->max_coc_px, "The scene's largest CoC radius in px (sets the f-stop)")
                   ->check(CLI::PositiveNumber);
  o->patterns_opt = cmd->add_option("--patterns", o->patterns, "Gather patterns NxK (e.g. 41x2 21x4)");
  cmd->add_option("--methods", o->methods, "Methods (default: every method in default sweeps)");
  cmd->add_option("--backend", o->backend, "gpu or cpu")->check(CLI::IsMember({"gpu", "cpu"}));
  o->method_options.add_to(cmd);
  o->sweep.add_to(cmd, 240);
  o->budget_opt = cmd->get_option("--budget-s");
  cmd->add_flag("--quick", o->quick, "Small grid for CI and tests (160x120)");
  cmd->callback([o] { tradeoff(*o); });
}

}  // namespace bokeh
