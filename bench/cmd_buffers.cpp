// `bokehbench buffers`: FLAG's 3D buffer at reduced precision and reduced resolution, memory, GPU
// frame time and error side by side (the paper's section 5: "Half resolution or quarter resolution 3D
// buffers could be used ... Further memory could be saved by decreasing the precision").
// Sweeps resolution x gather size x layer precision x buffer scale. For each configuration: the 3D
// buffer's bytes (paper convention and the driver's), the frame time (measure_method through Sweep),
// and the error against full-resolution f32 FLAG of the same scene (CPU, computed once per
// resolution and size); for context also against the exact scatter of the same radii (error_vs_exact:
// full-res FLAG carries the pattern of its k-px sample grid, which the reduced pipelines, sampling an
// s x s box-filtered image, do not reproduce, so "error vs full-res FLAG" overstates how much worse
// they look). Configurations whose 3D buffer exceeds --max-buffer-mb are listed as skipped and never
// allocated: lavapipe reports a heap but does not enforce it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "coc.hpp"
#include "commands.hpp"
#include "exact_scatter.hpp"
#include "flag_memory.hpp"
#include "flag_reduced.hpp"
#include "gpu/gpu_filters.hpp"
#include "metrics.hpp"
#include "parallel.hpp"
#include "pipeline.hpp"
#include "report.hpp"
#include "scene.hpp"
#include "sweep.hpp"
#include "vk/memory.hpp"

namespace bokeh {

namespace {

struct BuffersOptions {
  std::vector<std::string> resolutions = {"800x600", "1280x720", "1920x1080", "3840x2160"};
  std::vector<int> sizes = {21, 41};
  int spacing_px = 2;
  std::vector<std::string> precisions = {"f32", "f16", "r11g11b10f", "unorm10_bracketed", "unorm16_bracketed"};
  std::vector<int> scales = {1, 2, 4};
  double budget_s = 240;       // measuring time over all measured configurations
  double max_buffer_mb = 512;  // MiB of 3D buffer (driver's size) above which a configuration is skipped
  std::vector<double> budget_lines_mib = {64, 16};
  std::string scene = "hoops", device, out_dir = "results", plots_dir = "plots";
  int cpu_threads = default_cpu_threads();
  bool quick = false, plot = true, exact = true;
};

struct Resolution {
  int width = 0, height = 0;
  std::string text() const { return fmt::format("{}x{}", width, height); }
};

Resolution parse_resolution(const std::string& text) {
  const auto [width, height] = parse_int_pair(text, "resolution", "WIDTHxHEIGHT (e.g. 1920x1080)");
  const Resolution r{width, height};
  if (r.width < 16 || r.height < 16 || r.width > 16384 || r.height > 16384)
    throw std::invalid_argument("resolution '" + text + "' outside 16..16384 px per side");
  return r;
}

std::string describe_error(const nlohmann::json& e) {
  const auto& psnr = e["psnr_db"];
  return fmt::format("RMSE {:.3e}  PSNR {:>9}  max {:.3e}", e["rmse"].get<double>(),
                     psnr.is_null() ? "exact" : fmt::format("{:.2f} dB", psnr.get<double>()),
                     e["max_abs_error"].get<double>());
}

void buffers(BuffersOptions o) {
  if (o.quick) {
    o.resolutions = {"160x120"};
    o.sizes = {9, 13};
    o.budget_s = 12;
  }
  std::vector<Resolution> resolutions;
  for (const auto& r : o.resolutions) resolutions.push_back(parse_resolution(r));
  for (int n : o.sizes) validate(GatherPattern{n, o.spacing_px});
  for (const auto& p : o.precisions) layer_precision_from_string(p);
  for (int s : o.scales)
    if (s != 1 && s != 2 && s != 4) throw std::invalid_argument(fmt::format("--scales: {} is not 1, 2 or 4", s));
  if (!(o.max_buffer_mb > 0)) throw std::invalid_argument("--max-buffer-mb must be > 0");
  const FilterRegistration& flag = find_filter("flag");
  const auto wall_start = std::chrono::steady_clock::now();

  vk::Context ctx(o.device);
  const nlohmann::json context = run_context(&ctx.info());

  // Which configurations fit the budget is known before anything runs: the points measured share
  // the time budget.
  struct Config {
    Resolution res;
    GatherPattern pattern;
    std::string precision;
    int scale;
    FlagBufferExtent extent;
    std::uint64_t allocated = 0;
    std::string unavailable;  // why the driver cannot make this 3D image at all, if it cannot
  };
  std::vector<Config> grid;
  for (const auto& res : resolutions)
    for (int n : o.sizes)
      for (const auto& precision : o.precisions)
        for (int scale : o.scales) {
          const GatherPattern pattern{n, o.spacing_px};
          const FlagBufferExtent e = flag_buffer_extent(res.width, res.height, pattern, scale);
          Config c{res, pattern, precision, scale, e};
          try {  // creates the VkImage to ask its size, allocates nothing
            c.allocated = vk::image_3d_requirement_bytes(
                ctx, gpu::layer_format(layer_precision_from_string(precision)), e.width, e.height, e.layers);
          } catch (const std::exception& error) {
            c.unavailable = error.what();
          }
          grid.push_back(c);
        }
  auto over_budget = [&](const Config& c) { return c.allocated / kMiB > o.max_buffer_mb; };
  const auto measured = std::count_if(grid.begin(), grid.end(),
                                      [&](const Config& c) { return c.unavailable.empty() && !over_budget(c); });
  RepetitionPolicy policy;
  policy.point_budget_s = o.budget_s / std::max<double>(1.0, static_cast<double>(measured));
  policy.min_repetitions = 3;
  auto sweep = std::make_unique<Sweep>(o.out_dir + "/buffers_gbench.json", policy);

  fmt::print("buffers: {} at {}, N {}, k={}, precisions {}, scales {}; {} of {} configurations within {} MiB, "
             "device {}, LP_NUM_THREADS={}\n",
             o.scene, fmt::join(o.resolutions, ","), fmt::join(o.sizes, ","), o.spacing_px,
             fmt::join(o.precisions, ","), fmt::join(o.scales, ","), measured, grid.size(), o.max_buffer_mb,
             ctx.info().name, context["lp_num_threads"].get<std::string>());

  nlohmann::json points = nlohmann::json::array(), skipped = nlohmann::json::array(),
                 references = nlohmann::json::array();
  auto write = [&](const std::string& status) {
    write_results(
        o.out_dir + "/buffers.json", "bokehbench.buffers", context,
        {{"status", status},
         {"config",
          {{"scene", o.scene},
           {"resolutions", o.resolutions},
           {"sizes", o.sizes},
           {"spacing_px", o.spacing_px},
           {"precisions", o.precisions},
           {"scales", o.scales},
           {"budget_s", o.budget_s},
           {"max_buffer_mb", o.max_buffer_mb},
           {"budget_lines_mib", o.budget_lines_mib},
           {"scene_coc", "lens f-stop set per N so the scene's largest CoC radius equals k (N - 1) / 2"},
           {"memory",
            "buffer.paper_convention_bytes = W*H*ceil(N/2)*bytes_per_texel/scale^3 (the paper's 332/42/5.2 MB for "
            "f16); buffer.allocated_bytes = vkGetImageMemoryRequirements of the ceil(W/s) x ceil(H/s) x "
            "ceil(ceil(N/2)/s) 3D image, what --max-buffer-mb is checked against. other_bytes: bracket buffer and "
            "low-res 2D buffers"},
           {"error_reference",
            "CPU FLAG with f32 layers at full resolution, same scene, lens, N and k (flag_blur_in_strips, bit for bit "
            "flag_blur); metrics over RGB: rmse, psnr_db = 20 log10(reference max / rmse), null when exact (JSON "
            "has no infinity), max_abs_error. error_vs_exact: the same metrics against the exact scatter (energy "
            "sum, kernels/exact_scatter.hpp) of the same radii, for context (null with --no-exact)"},
           {"timing",
            "Vulkan timestamps around each pass of one submission (coc, downsample, bracket, horizontal, vertical, "
            "upsample as present), after a JIT warm-up; frame_ms over repetitions, each the mean of its "
            "iterations"}}},
         {"references", references},
         {"points", points},
         {"skipped", skipped},
         {"elapsed_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count()}});
  };

  std::size_t index = 0;
  std::optional<Scene> scene;
  std::string reference_key;
  Image reference, exact;
  Lens lens;
  for (const Config& c : grid) {
    ++index;
    if (Sweep::interrupted()) break;
    const LayerPrecision precision = layer_precision_from_string(c.precision);
    const std::string id = fmt::format("{}/N:{}/k:{}/{}/1:{}", c.res.text(), c.pattern.size_n, c.pattern.spacing_px,
                                       c.precision, c.scale);
    const double paper_bytes = flag_paper_bytes(c.res.width, c.res.height, c.pattern, precision, c.scale);
    const nlohmann::json buffer = {
        {"extent", {{"width", c.extent.width}, {"height", c.extent.height}, {"layers", c.extent.layers}}},
        {"bytes_per_texel", bytes_per_texel(precision)},
        {"paper_convention_bytes", paper_bytes},
        {"paper_convention_mib", paper_bytes / kMiB},
        {"texel_bytes", flag_texel_bytes(c.res.width, c.res.height, c.pattern, precision, c.scale)},
        {"allocated_bytes", c.allocated},
        {"allocated_mib", c.allocated / kMiB}};
    const nlohmann::json where = {{"id", id},           {"width_px", c.res.width}, {"height_px", c.res.height},
                                  {"N", c.pattern.size_n}, {"k", c.pattern.spacing_px}, {"precision", c.precision},
                                  {"scale", c.scale}};
    if (!c.unavailable.empty() || over_budget(c)) {
      nlohmann::json s = where;
      s["buffer"] = buffer;
      s["reason"] = !c.unavailable.empty() ? c.unavailable
                                           : fmt::format("3D buffer {:.1f} MiB over --max-buffer-mb {} (not allocated)",
                                                         c.allocated / kMiB, o.max_buffer_mb);
      skipped.push_back(s);
      fmt::print("[{:>3}/{}] {:<40} {:8.2f} MiB  skipped: {}\n", index, grid.size(), id, c.allocated / kMiB,
                 !c.unavailable.empty() ? c.unavailable : fmt::format("over the {} MiB budget", o.max_buffer_mb));
      write("partial");
      continue;
    }
    // The reference: once per resolution and gather size.
    const std::string key = fmt::format("{}/{}", c.res.text(), c.pattern.size_n);
    if (key != reference_key) {
      if (!scene || scene->color.width != c.res.width || scene->color.height != c.res.height)
        scene = make_scene(o.scene, c.res.width, c.res.height);
      lens = with_max_coc_radius(scene->lens, scene->depth_m, c.pattern.max_radius_px());
      const auto t0 = std::chrono::steady_clock::now();
      const CocInput coc = cpu_coc_pass(scene->color, scene->depth_m, lens, c.pattern);
      reference = flag_blur_in_strips(coc.packed, c.pattern, LayerPrecision::f32, 256, o.cpu_threads);
      reference_key = key;
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      nlohmann::json r = {{"width_px", c.res.width}, {"height_px", c.res.height}, {"N", c.pattern.size_n},
                          {"k", c.pattern.spacing_px}, {"f_stop", lens.f_stop}, {"cpu_s", seconds}};
      fmt::print("          reference {} N={}: CPU f32 FLAG, {:.1f} s\n", c.res.text(), c.pattern.size_n, seconds);
      if (o.exact) {
        // Ground truth for context: full-res FLAG samples every k-th pixel of full-res input, so its own
        // result carries that sampling's pattern; the reduced pipelines sample a box-filtered image.
        const auto t1 = std::chrono::steady_clock::now();
        exact = exact_scatter(scene->color, coc.radius_px, scene->depth_m, ScatterComposite::energy_sum,
                              o.cpu_threads);
        r["exact_cpu_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
        r["flag_f32_vs_exact"] = metrics_json(compare_images(reference, exact));
        fmt::print("          exact scatter (energy sum) {:.1f} s; full-res f32 FLAG vs it: {}\n",
                   r["exact_cpu_s"].get<double>(), describe_error(r["flag_f32_vs_exact"]));
      }
      references.push_back(r);
    }
    gpu::FilterOptions options{c.pattern, c.precision};
    options.buffer_scale = c.scale;
    try {
      Image output;
      const PointStats stats =
          measure_method(*sweep, "buffers/" + id, &ctx, flag, "gpu", *scene, lens, options, o.cpu_threads, &output);
      const nlohmann::json error = metrics_json(compare_images(output, reference));
      const nlohmann::json error_vs_exact =
          o.exact ? metrics_json(compare_images(output, exact)) : nlohmann::json(nullptr);
      const GatherPattern low = reduced_pattern(c.pattern, c.scale);
      std::uint64_t other = 0;
      if (is_bracketed(precision))
        other += gpu::flag_bracket_buffer_bytes(static_cast<std::uint32_t>(c.extent.height),
                                                static_cast<std::uint32_t>(c.extent.layers));
      if (c.scale > 1) other += 2ull * c.extent.width * c.extent.height * 16;
      // The CoC pass is the same for every configuration of a resolution and N (and dominates at 4K on
      // lavapipe): the FLAG passes alone are what precision and scale change.
      double flag_ms = 0;
      for (const auto& [pass, ms] : stats.pass_ms)
        if (pass != "coc") flag_ms += ms;
      nlohmann::json p = where;
      p.update({{"bytes_per_texel", bytes_per_texel(precision)},
                {"low_res_N", low.size_n},
                {"max_radius_px", c.pattern.max_radius_px()},
                {"low_res_max_radius_px", low.max_radius_px() * static_cast<float>(c.scale)},
                {"buffer", buffer},
                {"other_bytes", other},
                {"fits_mib", nlohmann::json::array()},
                {"frame_ms", distribution_json(stats.frame_ms)},
                {"pass_ms", stats.pass_ms},
                {"flag_passes_ms", flag_ms},
                {"repetitions", stats.repetitions},
                {"iterations_per_repetition", stats.iterations_per_repetition},
                {"measure_wall_s", stats.wall_s},
                {"error", error},
                {"error_vs_exact", error_vs_exact}});
      for (double mib : o.budget_lines_mib)
        if (c.allocated / kMiB <= mib) p["fits_mib"].push_back(mib);
      points.push_back(p);
      fmt::print("[{:>3}/{}] {:<40} {:8.2f} MiB  frame {:9.2f} ms (FLAG passes {:8.2f})  {}\n", index, grid.size(), id,
                 c.allocated / kMiB, stats.frame_ms.median, flag_ms, describe_error(error));
    } catch (const std::exception& e) {
      nlohmann::json s = where;
      s["buffer"] = buffer;
      s["reason"] = e.what();
      skipped.push_back(s);
      fmt::print("[{:>3}/{}] {:<40} skipped: {}\n", index, grid.size(), id, e.what());
    }
    std::fflush(stdout);
    write("partial");
  }
  const bool complete = !Sweep::interrupted();
  sweep.reset();  // closes buffers_gbench.json
  write(complete ? "complete" : "interrupted");

  // Which configurations fit each budget line, fastest first.
  for (double mib : o.budget_lines_mib) {
    fmt::print("\nWithin {} MiB of 3D buffer (fastest first):\n", mib);
    std::vector<const nlohmann::json*> fit;
    for (const auto& p : points)
      if (p["buffer"]["allocated_mib"].get<double>() <= mib) fit.push_back(&p);
    std::sort(fit.begin(), fit.end(), [](const nlohmann::json* a, const nlohmann::json* b) {
      return (*a)["frame_ms"]["median"].get<double>() < (*b)["frame_ms"]["median"].get<double>();
    });
    for (const auto* p : fit)
      fmt::print("  {:<40} {:8.2f} MiB  frame {:9.2f} ms (FLAG passes {:8.2f})  {}\n", (*p)["id"].get<std::string>(),
                 (*p)["buffer"]["allocated_mib"].get<double>(), (*p)["frame_ms"]["median"].get<double>(),
                 (*p)["flag_passes_ms"].get<double>(), describe_error((*p)["error"]));
  }
  fmt::print("wrote {}/buffers.json ({:.0f} s)\n", o.out_dir,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count());
  if (!complete) throw std::runtime_error("interrupted: finished configurations are in " + o.out_dir + "/buffers.json");
  if (o.plot) run_plot_script("plot_buffers.py", o.out_dir + "/buffers.json", o.plots_dir + "/buffers");
}

}  // namespace

void add_buffers_command(CLI::App& app) {
  auto o = std::make_shared<BuffersOptions>();
  auto* cmd = app.add_subcommand(
      "buffers", "FLAG 3D buffer at reduced precision and resolution: memory, GPU time and error side by side");
  cmd->add_option("--resolutions", o->resolutions, "Frame sizes WIDTHxHEIGHT");
  cmd->add_option("--sizes", o->sizes, "Gather sizes N (odd)");
  cmd->add_option("--spacing,-k", o->spacing_px, "Sample spacing k in px");
  cmd->add_option("--precisions", o->precisions, "3D-buffer precisions")
      ->check(CLI::IsMember({"f32", "f16", "r11g11b10f", "unorm10_bracketed", "unorm16_bracketed"}));
  cmd->add_option("--scales", o->scales, "Buffer scales: 1 full, 2 half, 4 quarter")->check(CLI::IsMember({1, 2, 4}));
  cmd->add_option("--budget-s", o->budget_s, "Measuring time to aim for, spread over the measured configurations")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-buffer-mb", o->max_buffer_mb,
                  "Skip (never allocate) configurations whose 3D buffer exceeds this many MiB")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--budget-lines", o->budget_lines_mib, "Memory budgets (MiB) to report and draw")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--scene", o->scene, "Procedural scene")->check(CLI::IsMember(procedural_scene_names()));
  cmd->add_option("--cpu-threads", o->cpu_threads, "Threads for the CPU reference")->check(CLI::Range(1, 1024));
  cmd->add_option("--device", o->device, "Vulkan device index or name part");
  cmd->add_option("--out-dir", o->out_dir, "Where buffers.json and buffers_gbench.json go");
  cmd->add_option("--plots-dir", o->plots_dir, "Where buffers.png and .svg go");
  cmd->add_flag("--quick", o->quick, "Small sweep for CI and tests (160x120, N = 9 and 13)");
  cmd->add_flag("!--no-plot", o->plot, "Skip the plot");
  cmd->add_flag("!--no-exact", o->exact,
                "Skip the exact-scatter ground truth (error_vs_exact; ~20 s per N at 4K on two cores)");
  cmd->callback([o] { buffers(*o); });
}

}  // namespace bokeh
