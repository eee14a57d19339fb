// `bokehbench figure9`: FLAG paper Figure 9, frame time vs gather size for each method, on the
// Vulkan device and as CPU references, with spread, fitted growth exponents and naive/FLAG ratios.
#include <chrono>
#include <cstdlib>
#include <map>
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
#include "sweep.hpp"

namespace bokeh {

namespace {

struct Figure9Options {
  std::vector<int> sizes = {5, 9, 13, 17, 21, 25, 29, 33, 37, 41};
  int spacing_px = 2, width_px = 800, height_px = 600;
  std::string scene = "hoops", precision, device;
  std::vector<std::string> methods = {"naive", "flag", "circular1", "circular2"};
  std::vector<std::string> backends = {"gpu", "cpu"};
  double budget_s = 300;
  int cpu_threads = default_cpu_threads();
  std::string out_dir = "results", plots_dir = "plots", reference_cache = "build/reference-cache";
  bool quick = false, plot = true;
  int near_components = 0;  // circular filters: near-field components (0: the method's)
};

nlohmann::json fit_json(const PowerLawFit& f) {
  return {{"exponent", f.exponent}, {"coefficient_ms", f.coefficient}, {"r_squared", f.r_squared}, {"points", f.points}};
}

// Exponent of frame time vs N over all sizes and over the larger half (where fixed costs such as
// the CoC pass no longer dominate).
nlohmann::json fits_for(const nlohmann::json& series) {
  std::vector<double> n, ms;
  for (const auto& p : series) n.push_back(p["N"].get<double>()), ms.push_back(p["frame_ms"]["median"].get<double>());
  nlohmann::json fits = nlohmann::json::object();
  if (n.size() >= 2) fits["all_sizes"] = fit_json(fit_power_law(n, ms));
  const std::size_t half = n.size() / 2;
  if (n.size() - half >= 2)
    fits["larger_half"] = fit_json(fit_power_law({n.begin() + half, n.end()}, {ms.begin() + half, ms.end()}));
  return fits;
}

nlohmann::json ratios_for(const nlohmann::json& series_list, const std::string& backend) {
  nlohmann::json ratios = nlohmann::json::array();
  const nlohmann::json *naive = nullptr, *flag = nullptr;
  for (const auto& s : series_list) {
    if (s["backend"] != backend) continue;
    if (s["method"] == "naive") naive = &s["points"];
    if (s["method"] == "flag") flag = &s["points"];
  }
  if (!naive || !flag) return ratios;
  for (const auto& a : *naive)
    for (const auto& b : *flag)
      if (a["N"] == b["N"])
        ratios.push_back({{"N", a["N"]},
                          {"backend", backend},
                          {"naive_over_flag", a["frame_ms"]["median"].get<double>() / b["frame_ms"]["median"].get<double>()}});
  return ratios;
}

void figure9(Figure9Options o) {
  if (o.quick) {
    o.sizes = {5, 9, 13};
    o.width_px = 200, o.height_px = 150;
    o.budget_s = 20;
  }
  for (int n : o.sizes) validate(GatherPattern{n, o.spacing_px});
  for (const auto& m : o.methods) find_filter(m);
  const auto wall_start = std::chrono::steady_clock::now();

  const Scene scene = make_scene(o.scene, o.width_px, o.height_px);
  const bool any_gpu = std::find(o.backends.begin(), o.backends.end(), "gpu") != o.backends.end();
  std::optional<vk::Context> ctx;
  if (any_gpu) ctx.emplace(o.device);
  const nlohmann::json context = run_context(ctx ? &ctx->info() : nullptr);

  const std::size_t total = o.methods.size() * o.backends.size() * o.sizes.size();
  RepetitionPolicy policy;
  policy.point_budget_s = o.budget_s / static_cast<double>(total);
  auto sweep = std::make_unique<Sweep>(o.out_dir + "/figure9_gbench.json", policy);

  fmt::print("Figure 9: {} {}x{}, k={}, sizes {}, device {}, LP_NUM_THREADS={}\n", o.scene, o.width_px, o.height_px,
             o.spacing_px, fmt::join(o.sizes, ","), ctx ? ctx->info().name : "none",
             context["lp_num_threads"].get<std::string>());

  nlohmann::json series_list = nlohmann::json::array(), skipped = nlohmann::json::array();
  auto write = [&](bool complete) {
    for (auto& s : series_list) s["fits"] = fits_for(s["points"]);
    nlohmann::json ratios = nlohmann::json::array();
    for (const auto& backend : o.backends)
      for (const auto& r : ratios_for(series_list, backend)) ratios.push_back(r);
    write_results(
        o.out_dir + "/figure9.json", "bokehbench.figure9", context,
        {{"status", complete ? "complete" : (Sweep::interrupted() ? "interrupted" : "partial")},
         {"config",
          {{"scene", o.scene}, {"width_px", o.width_px}, {"height_px", o.height_px}, {"spacing_px", o.spacing_px},
           {"sizes", o.sizes}, {"precision_override", o.precision}, {"cpu_threads", o.cpu_threads},
           {"budget_s", o.budget_s},
           {"scene_coc", "lens f-stop set per N so the scene's largest CoC radius equals the pattern's max radius"},
           {"error", "each point's output against the exact scatter references (energy_sum: the plain sum naive and "
                     "FLAG approximate; depth_ordered: composited front to back) of the same scene and CoC; PSNR peak "
                     "= the reference's max value, null when exact"},
           {"timing",
            "gpu: Vulkan timestamps around each pass of one submission, after a JIT warm-up; cpu: wall clock. "
            "frame_ms is the distribution over repetitions, each the mean of its iterations"}}},
         {"series", series_list},
         {"naive_over_flag", ratios},
         {"skipped", skipped},
         {"elapsed_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count()}});
  };

  // Exact references per gather size (the lens, hence the CoC, follows N), computed once and cached.
  ExactReferenceCache cache(o.reference_cache);
  std::map<int, ExactReferences> references;
  auto references_for = [&](int n, const Lens& lens) -> const ExactReferences& {
    auto it = references.find(n);
    if (it == references.end())
      it = references.emplace(n, exact_references(scene, lens, GatherPattern{n, o.spacing_px}.max_radius_px(), cache)).first;
    return it->second;
  };

  std::size_t index = 0;
  for (const auto& method : o.methods) {
    const FilterRegistration& filter = find_filter(method);
    // --precision applies to the methods that accept it; the others keep their default.
    const auto& accepted = filter.precisions;
    const std::string precision = std::find(accepted.begin(), accepted.end(), o.precision) != accepted.end()
                                      ? o.precision
                                      : accepted.front();
    for (const auto& backend : o.backends) {
      nlohmann::json series = {{"method", method}, {"backend", backend}, {"precision", precision},
                               {"points", nlohmann::json::array()}};
      series_list.push_back(series);
      for (int n : o.sizes) {
        ++index;
        if (Sweep::interrupted()) break;
        gpu::FilterOptions options{{n, o.spacing_px}, precision};
        options.near_components = o.near_components;
        const std::string name = fmt::format("figure9/{}/{}/N:{}/k:{}", method, backend, n, o.spacing_px);
        try {
          const Lens lens = with_max_coc_radius(scene.lens, scene.depth_m, options.pattern.max_radius_px());
          Image output;
          const PointStats stats = measure_method(*sweep, name, ctx ? &*ctx : nullptr, filter, backend, scene, lens,
                                                  options, o.cpu_threads, &output);
          const nlohmann::json error = error_json(output, references_for(n, lens));
          series_list.back()["points"].push_back(
              {{"N", n},
               {"k", o.spacing_px},
               {"max_radius_px", options.pattern.max_radius_px()},
               {"samples_per_pixel", filter.samples_per_pixel(options)},
               {"f_stop", lens.f_stop},
               {"frame_ms", distribution_json(stats.frame_ms)},
               {"pass_ms", stats.pass_ms},
               {"repetitions", stats.repetitions},
               {"iterations_per_repetition", stats.iterations_per_repetition},
               {"measure_wall_s", stats.wall_s},
               {"error", error}});
          fmt::print("[{:>3}/{}] {:<28} median {:10.3f} ms  IQR {:.3f}-{:.3f}  ({} reps x {} frames, {:.1f} s)  PSNR {}\n",
                     index, total, name, stats.frame_ms.median, stats.frame_ms.q1, stats.frame_ms.q3,
                     stats.repetitions, stats.iterations_per_repetition, stats.wall_s,
                     psnr_text(error["vs_energy_sum"]));
        } catch (const std::exception& e) {
          skipped.push_back({{"method", method}, {"backend", backend}, {"N", n}, {"reason", e.what()}});
          fmt::print("[{:>3}/{}] {:<28} skipped: {}\n", index, total, name, e.what());
        }
        std::fflush(stdout);
        write(false);
      }
    }
  }
  const bool complete = !Sweep::interrupted();
  sweep.reset();  // closes figure9_gbench.json
  write(complete);
  fmt::print("wrote {}/figure9.json and {}/figure9_gbench.json ({:.0f} s)\n", o.out_dir, o.out_dir,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count());
  if (!complete) throw std::runtime_error("interrupted: finished points are in " + o.out_dir + "/figure9.json");

  if (o.plot) run_plot_script("plot_figure9.py", o.out_dir + "/figure9.json", o.plots_dir + "/figure9");
}

}  // namespace

void add_figure9_command(CLI::App& app) {
  auto o = std::make_shared<Figure9Options>();
  auto* cmd = app.add_subcommand("figure9", "Reproduce FLAG paper Figure 9: frame time vs gather size");
  cmd->add_option("--sizes", o->sizes, "Gather sizes N (odd)");
  cmd->add_option("--spacing,-k", o->spacing_px, "Sample spacing k in px (the paper uses 2)");
  cmd->add_option("--width", o->width_px, "Image width in px")->check(CLI::Range(16, 16384));
  cmd->add_option("--height", o->height_px, "Image height in px")->check(CLI::Range(16, 16384));
  cmd->add_option("--scene", o->scene, "Procedural scene")->check(CLI::IsMember(procedural_scene_names()));
  cmd->add_option("--methods", o->methods, "Methods to sweep");
  cmd->add_option("--backends", o->backends, "gpu and/or cpu")->check(CLI::IsMember({"gpu", "cpu"}));
  cmd->add_option("--precision", o->precision,
                  "Intermediate storage for the methods that accept it (default: each method's, FLAG: f16 as the paper)");
  cmd->add_option("--near-components", o->near_components,
                  "Circular filters: near-field components (default: the method's N; circular2 with 1 is Garcia's)")
      ->check(CLI::Range(1, 6));
  cmd->add_option("--budget-s", o->budget_s, "Measuring time to aim for, spread over the points")->check(CLI::PositiveNumber);
  cmd->add_option("--cpu-threads", o->cpu_threads, "Threads for the CPU references")->check(CLI::Range(1, 1024));
  cmd->add_option("--device", o->device, "Vulkan device index or name part");
  cmd->add_option("--out-dir", o->out_dir, "Where figure9.json and figure9_gbench.json go");
  cmd->add_option("--plots-dir", o->plots_dir, "Where figure9.png and .svg go");
  cmd->add_option("--reference-cache", o->reference_cache, "Directory caching the exact references");
  cmd->add_flag("--quick", o->quick, "Small sweep for CI and tests (200x150, N = 5, 9, 13)");
  cmd->add_flag("!--no-plot", o->plot, "Skip the plot");
  cmd->callback([o] { figure9(*o); });
}

}  // namespace bokeh
