// `bokehbench tradeoff`: time per frame against error for every configuration of every method on one
// scene (precisions, buffer scales, patterns and each method's own speed/quality options), measured
// interleaved, with the Pareto front (fastest for its accuracy) drawn and listed.
#include <algorithm>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "commands.hpp"
#include "intervals.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "stats.hpp"
#include "roofline.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct TradeoffOptions {
  AxisFlags axes;
  double max_coc_px = 40;
  SweepFlags sweep;
  MethodOptionFlags method_options;
  CLI::Option* coc_opt = nullptr;
};

// The aperture a point drew (files from before apertures: the disc).
std::string aperture_of(const nlohmann::json& point) {
  return point.contains("aperture") ? point["aperture"]["name"].get<std::string>() : "disc";
}

// Configurations nothing beats on both median time and PSNR (exact = +inf), fastest first, among the
// points of each aperture (each is scored against its own shape's exact reference, so points of two
// apertures answer different questions). PSNRs within 0.1 dB count as the same accuracy (e.g. FLAG f16
// vs f32 on the same pattern): no one can see that difference, so it should not buy a slower
// configuration a place on the front.
nlohmann::json pareto_ids(const nlohmann::json& points) {
  std::vector<std::string> apertures;
  for (const auto& c : points)
    if (std::find(apertures.begin(), apertures.end(), aperture_of(c)) == apertures.end())
      apertures.push_back(aperture_of(c));
  nlohmann::json front = nlohmann::json::array();
  for (const auto& aperture : apertures) {
    std::vector<double> time_ms, psnr_db;
    std::vector<nlohmann::json> ids;
    for (const auto& c : points) {
      if (aperture_of(c) != aperture) continue;
      time_ms.push_back(c["frame_ms"]["median"].get<double>());
      psnr_db.push_back(psnr_for_ranking(c["error"]["vs_energy_sum"]));
      ids.push_back(c["id"]);
    }
    for (std::size_t i : pareto_front(time_ms, psnr_db, 0.1)) front.push_back(ids[i]);
  }
  return front;
}

void tradeoff(TradeoffOptions& o) {
  o.axes.resolve(&o.sweep);
  if (o.axes.quick && !given(o.coc_opt)) o.max_coc_px = 8;
  if (o.axes.methods.empty()) o.axes.methods = default_sweep_methods();
  Axes axes;
  axes.methods = o.axes.methods;
  axes.backends = o.axes.backends;
  axes.scenes = o.axes.scenes;
  axes.resolutions = o.axes.frame_sizes();
  axes.patterns = o.axes.patterns();
  axes.precisions = {"all"};
  axes.scales = {0};
  axes.option_values = o.method_options.values_for(axes.methods);
  axes.sweep_options = true;
  axes.max_coc_px = {o.max_coc_px};
  axes.apertures = o.axes.aperture_shapes();

  SweepSettings s = o.sweep.settings("tradeoff", "plot_tradeoff.py");
  s.config = {{"scene", axes.scenes.front()},
              {"width_px", axes.resolutions.front().width_px},
              {"height_px", axes.resolutions.front().height_px},
              {"max_coc_px", o.max_coc_px},
              {"backend", axes.backends.front()},
              {"patterns", o.axes.sizes},
              {"spacing_px", o.axes.spacing_px},
              {"methods", axes.methods},
              {"apertures", o.axes.apertures},
              {"pareto", "minimise frame_ms median, maximise PSNR vs the energy_sum exact reference"}};
  s.derive = derive_tradeoff;
  s.summary = [](const nlohmann::json& doc) {
    fmt::print("\nPareto front (fastest first: nothing is both faster and more accurate; each aperture its own; "
               "median frame time [95% interval]; \"as fast\": its interval overlaps the faster entry's, so the "
               "extra accuracy is not shown to cost time):\n");
    std::string shown;
    double faster_high = 0;  // the interval's upper end of the front's previous (faster) entry
    for (const auto& id : doc["pareto_front"])
      for (const auto& c : doc["points"])
        if (c["id"] == id) {
          const bool first = aperture_of(c) != shown;
          if (first) fmt::print(" aperture {}:\n", shown = aperture_of(c));
          const auto& t = c["frame_ms_interval"];
          fmt::print("  for {:>24} ms you can have at best {:>9}  ({}){}\n", interval_text(t, 2),
                     psnr_text(c["error"]["vs_energy_sum"]), id.get<std::string>(),
                     !first && t["low"].get<double>() <= faster_high ? "  as fast" : "");
          faster_high = t["high"].get<double>();
        }
    print_roofline(doc);
  };
  o.sweep.apply_shard(axes);
  run_sweep(expand(axes), s);
}

}  // namespace

void derive_tradeoff(nlohmann::json& doc) { doc["pareto_front"] = pareto_ids(doc["points"]); }

void add_tradeoff_command(CLI::App& app) {
  auto o = std::make_shared<TradeoffOptions>();
  auto* cmd = app.add_subcommand("tradeoff", "Time vs error for every configuration, with the Pareto front");
  AxisFlags& a = o->axes;
  a.sizes = {"41x2", "21x4", "11x8"};  // each covers max_coc_px when k (N - 1) / 2 equals it
  a.resolutions = {"800x600"};
  a.scenes = {"hoops"};
  a.backends = {"gpu"};
  a.add_to(cmd, {Axis::sizes, Axis::methods, Axis::apertures}, {Axis::resolutions, Axis::scenes, Axis::backends});
  o->coc_opt = cmd->add_option("--max-coc", o->max_coc_px, "The scene's largest CoC radius in px (sets the f-stop)")
                   ->check(finite_number())
                   ->check(CLI::PositiveNumber);
  o->method_options.add_to(cmd);
  o->sweep.add_to(cmd, 240);
  a.add_quick(cmd, "Small grid for CI and tests (160x120, patterns 9x2 and 5x4, max CoC 8 px, 15 s)",
              {{Axis::resolutions, {"160x120"}}, {Axis::sizes, {"9x2", "5x4"}}}, 15);
  cmd->callback([o] { tradeoff(*o); });
}

}  // namespace bokeh
