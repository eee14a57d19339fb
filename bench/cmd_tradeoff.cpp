// `bokehbench tradeoff`: time per frame against error for a grid of configurations on one scene,
// with the Pareto front (fastest for its accuracy) drawn and listed.
#include <algorithm>
#include <chrono>
#include <optional>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "coc.hpp"
#include "commands.hpp"
#include "parallel.hpp"
#include "pipeline.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "stats.hpp"

namespace bokeh {

namespace {

struct TradeoffOptions {
  std::string scene = "hoops", backend = "gpu", device, out_dir = "results", plots_dir = "plots";
  std::string reference_cache = "build/reference-cache";
  int width_px = 800, height_px = 600;
  double max_coc_px = 40;
  // Gather patterns as NxK; each covers max_coc_px when k (N - 1) / 2 equals it.
  std::vector<std::string> patterns = {"41x2", "21x4", "11x8"};
  std::vector<std::string> methods;  // default: every registered method
  double budget_s = 240;
  bool quick = false, plot = true;
};

GatherPattern parse_pattern(const std::string& text) {
  const auto [size_n, spacing_px] = parse_int_pair(text, "pattern", "NxK (e.g. 41x2)");
  const GatherPattern p{size_n, spacing_px};
  validate(p);
  return p;
}

// Configurations nothing beats on both median time and PSNR (exact = +inf), fastest first. PSNRs
// within 0.1 dB count as the same accuracy (e.g. FLAG f16 vs f32 on the same pattern): no one can
// see that difference, so it should not buy a slower configuration a place on the front.
std::vector<std::size_t> pareto_front(const nlohmann::json& configs) {
  std::vector<double> time_ms, psnr_db;
  for (const auto& c : configs) {
    time_ms.push_back(c["frame_ms"]["median"].get<double>());
    psnr_db.push_back(psnr_for_ranking(c["error"]["vs_energy_sum"]));
  }
  return bokeh::pareto_front(time_ms, psnr_db, 0.1);
}

void tradeoff(TradeoffOptions o) {
  if (o.quick) o.width_px = 160, o.height_px = 120, o.max_coc_px = 8, o.patterns = {"9x2", "5x4"}, o.budget_s = 15;
  if (o.methods.empty())
    for (const auto& f : registered_filters()) o.methods.push_back(f.name);
  std::vector<GatherPattern> patterns;
  for (const auto& p : o.patterns) patterns.push_back(parse_pattern(p));

  const auto wall_start = std::chrono::steady_clock::now();
  Scene scene = make_scene(o.scene, o.width_px, o.height_px);
  scene.lens = with_max_coc_radius(scene.lens, scene.depth_m, o.max_coc_px);
  std::optional<vk::Context> ctx;
  if (o.backend == "gpu") ctx.emplace(o.device);
  const nlohmann::json context = run_context(ctx ? &ctx->info() : nullptr);

  // Every configuration: method x precision x pattern (a method whose kernel only depends on the max
  // radius, not on the sample grid, takes the first pattern only).
  struct Config {
    const FilterRegistration* filter;
    gpu::FilterOptions options;
  };
  std::vector<Config> grid;
  for (const auto& name : o.methods) {
    const FilterRegistration& filter = find_filter(name);
    for (const auto& precision : filter.precisions)
      for (int scale : filter.buffer_scales)
        for (const auto& pattern : patterns) {
          gpu::FilterOptions options{pattern, precision};
          options.buffer_scale = scale;
          grid.push_back({&filter, options});
          if (!filter.samples_pattern) break;
        }
  }

  fmt::print("tradeoff: {} {}x{}, max CoC {} px, {} configurations on {}\n", o.scene, o.width_px, o.height_px,
             o.max_coc_px, grid.size(), ctx ? ctx->info().name : "cpu");
  ExactReferenceCache cache(o.reference_cache);
  const ExactReferences refs = exact_references(scene, scene.lens, static_cast<float>(o.max_coc_px), cache);

  RepetitionPolicy policy;
  policy.point_budget_s = o.budget_s / static_cast<double>(grid.size());
  auto sweep = std::make_unique<Sweep>(o.out_dir + "/tradeoff_gbench.json", policy);
  nlohmann::json configs = nlohmann::json::array(), skipped = nlohmann::json::array();
  auto write = [&](const std::string& status) {
    nlohmann::json front = nlohmann::json::array();
    for (std::size_t i : pareto_front(configs)) front.push_back(configs[i]["id"]);
    write_results(o.out_dir + "/tradeoff.json", "bokehbench.tradeoff", context,
                  {{"status", status},
                   {"config",
                    {{"scene", o.scene}, {"width_px", o.width_px}, {"height_px", o.height_px},
                     {"max_coc_px", o.max_coc_px}, {"f_stop", scene.lens.f_stop}, {"backend", o.backend},
                     {"patterns", o.patterns}, {"budget_s", o.budget_s},
                     {"pareto", "minimise frame_ms median, maximise PSNR vs the energy_sum exact reference"}}},
                   {"configurations", configs},
                   {"pareto_front", front},
                   {"skipped", skipped},
                   {"elapsed_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count()}});
  };

  for (std::size_t i = 0; i < grid.size() && !Sweep::interrupted(); ++i) {
    const Config& c = grid[i];
    const std::string id =
        fmt::format("{}/{}{}/N:{}/k:{}", c.filter->name, c.options.precision,
                    c.options.buffer_scale > 1 ? fmt::format("/scale:1-{}", c.options.buffer_scale) : "",
                    c.options.pattern.size_n, c.options.pattern.spacing_px);
    try {
      Image output;
      const PointStats stats = measure_method(*sweep, "tradeoff/" + o.backend + "/" + id, ctx ? &*ctx : nullptr,
                                              *c.filter, o.backend, scene, scene.lens, c.options,
                                              default_cpu_threads(), &output);
      const nlohmann::json error = error_json(output, refs);
      configs.push_back({{"id", id},
                         {"method", c.filter->name},
                         {"precision", c.options.precision},
                         {"buffer_scale", c.options.buffer_scale},
                         {"N", c.options.pattern.size_n},
                         {"k", c.options.pattern.spacing_px},
                         {"max_radius_px", c.options.pattern.max_radius_px()},
                         {"samples_per_pixel", c.filter->samples_per_pixel(c.options)},
                         {"frame_ms", distribution_json(stats.frame_ms)},
                         {"pass_ms", stats.pass_ms},
                         {"repetitions", stats.repetitions},
                         {"error", error}});
      fmt::print("[{:>3}/{}] {:<32} {:10.3f} ms  PSNR {:>9}  SSIM {}\n", i + 1, grid.size(), id,
                 stats.frame_ms.median, psnr_text(error["vs_energy_sum"]), error["vs_energy_sum"]["ssim"].dump());
    } catch (const std::exception& e) {
      skipped.push_back({{"id", id}, {"reason", e.what()}});
      fmt::print("[{:>3}/{}] {:<32} skipped: {}\n", i + 1, grid.size(), id, e.what());
    }
    std::fflush(stdout);
    write("partial");
  }
  sweep.reset();
  const bool complete = !Sweep::interrupted();
  write(complete ? "complete" : "interrupted");
  fmt::print("\nPareto front (fastest first: nothing is both faster and more accurate):\n");
  for (std::size_t i : pareto_front(configs)) {
    const auto& c = configs[i];
    fmt::print("  for {:9.2f} ms you can have at best {:>9}  ({})\n", c["frame_ms"]["median"].get<double>(),
               psnr_text(c["error"]["vs_energy_sum"]), c["id"].get<std::string>());
  }
  fmt::print("wrote {}/tradeoff.json\n", o.out_dir);
  if (!complete) throw std::runtime_error("interrupted: finished configurations are in " + o.out_dir + "/tradeoff.json");
  if (o.plot) run_plot_script("plot_tradeoff.py", o.out_dir + "/tradeoff.json", o.plots_dir + "/tradeoff");
}

}  // namespace

void add_tradeoff_command(CLI::App& app) {
  auto o = std::make_shared<TradeoffOptions>();
  auto* cmd = app.add_subcommand("tradeoff", "Time vs error for every configuration, with the Pareto front");
  cmd->add_option("--scene", o->scene, "Procedural scene")->check(CLI::IsMember(procedural_scene_names()));
  cmd->add_option("--width", o->width_px, "Image width in px")->check(CLI::Range(16, 16384));
  cmd->add_option("--height", o->height_px, "Image height in px")->check(CLI::Range(16, 16384));
  cmd->add_option("--max-coc", o->max_coc_px, "The scene's largest CoC radius in px (sets the f-stop)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--patterns", o->patterns, "Gather patterns NxK (e.g. 41x2 21x4)");
  cmd->add_option("--methods", o->methods, "Methods (default: all registered)");
  cmd->add_option("--backend", o->backend, "gpu or cpu")->check(CLI::IsMember({"gpu", "cpu"}));
  cmd->add_option("--budget-s", o->budget_s, "Measuring time to aim for, spread over the configurations")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--device", o->device, "Vulkan device index or name part");
  cmd->add_option("--out-dir", o->out_dir, "Where tradeoff.json goes");
  cmd->add_option("--plots-dir", o->plots_dir, "Where tradeoff.png and .svg go");
  cmd->add_option("--reference-cache", o->reference_cache, "Directory caching the exact references");
  cmd->add_flag("--quick", o->quick, "Small grid for CI and tests (160x120)");
  cmd->add_flag("!--no-plot", o->plot, "Skip the plot");
  cmd->callback([o] { tradeoff(*o); });
}

}  // namespace bokeh
