// `bokehbench render`: one image through one method, so a user can look at what is being timed.
#include <chrono>
#include <optional>

#include <filesystem>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "coc.hpp"
#include "image_io.hpp"
#include "parallel.hpp"
#include "commands.hpp"
#include "run.hpp"
#include "scene.hpp"

namespace bokeh {

namespace {

struct RenderOptions {
  std::string scene_name = "hoops";
  std::string color_path, depth_path, lens_path, method = "flag", precision, backend = "gpu", device;
  std::string out_path = "render.png";
  int width_px = 800, height_px = 600, size_n = 41, spacing_px = 2;
  std::optional<double> fit_max_coc_px;
  MethodOptionFlags method_options;
  int buffer_scale = 1;
  bool compare = false;
  std::string reference_cache = "build/reference-cache";
};

// Beside OUT: OUT_compare.png with the exact reference, the result and an error heat map, so a
// person can see where a method fails (edges, highlights, large radii).
void write_comparison(const Scene& scene, const Image& result, float max_radius_px, const RenderOptions& o) {
  ExactReferenceCache cache(o.reference_cache);
  const ExactReferences refs = exact_references(scene, scene.lens, max_radius_px, cache);
  const nlohmann::json error = error_json(result, refs);
  for (const char* which : {"vs_energy_sum", "vs_depth_ordered"}) {
    const auto& m = error[which];
    auto number = [&](const char* key, const char* format) {
      return m[key].is_null() ? std::string("n/a") : fmt::format(fmt::runtime(format), m[key].get<double>());
    };
    fmt::print("  {:<17} PSNR {:>8}  RMSE {}  max |err| {}  energy err {}  SSIM {}\n", which,
               psnr_text(m),
               number("rmse", "{:.4g}"), number("max_abs_error", "{:.4g}"),
               number("mean_relative_energy_error", "{:.2e}"), number("ssim", "{:.4f}"));
  }
  const std::filesystem::path out(o.out_path);
  const std::string sheet_path = (out.parent_path() / (out.stem().string() + "_compare.png")).string();
  write_display_image(contact_sheet({{"exact scatter (energy sum)", to_display_srgb(refs.energy_sum)},
                                     {o.method + " (" + o.backend + ")", to_display_srgb(result)},
                                     {"|error| of luminance (99th pct = top)", error_heat_map(result, refs.energy_sum)}}),
                      sheet_path);
  fmt::print("wrote {}\n", sheet_path);
}

void render(RenderOptions& o) {
  Scene scene = o.color_path.empty() ? make_scene(o.scene_name, o.width_px, o.height_px)
                                     : load_scene(o.color_path, o.depth_path);
  if (!o.lens_path.empty()) scene.lens = load_lens_json(o.lens_path);
  const Method& method = find_method(o.method);
  FilterOptions options = method.defaults({o.size_n, o.spacing_px});
  if (!o.precision.empty()) options.precision = o.precision;
  options.buffer_scale = o.buffer_scale;
  for (const auto& [key, value] : o.method_options.values_for({o.method})) options.values[key] = value;
  check_options(method, options);
  if (o.fit_max_coc_px) scene.lens = with_max_coc_radius(scene.lens, scene.depth_m, *o.fit_max_coc_px);

  fmt::print("{} {}x{}, {} ({}) on {}, N={} k={} (max radius {} px), f/{:.3g} focus {} m\n", scene.name,
             scene.color.width, scene.color.height, o.method, options.precision, o.backend, o.size_n, o.spacing_px,
             options.pattern.max_radius_px(),
             scene.lens.f_stop, scene.lens.focus_distance_m);
  Image result;
  nlohmann::json stats;
  if (o.backend == "gpu") {
    vk::Context ctx(o.device, method.needs(options));
    std::vector<vk::PassTime> passes;
    result = run_gpu(ctx, method, scene.color, scene.depth_m, scene.lens, options, &passes, &stats);
    fmt::print("device: {} ({})\n", ctx.info().name, ctx.info().driver_info);
    for (const auto& p : passes) fmt::print("  {:<12} {:9.3f} ms\n", p.pass, p.ms);
    fmt::print("  {:<12} {:9.3f} ms (one frame after warm-up)\n", "frame", vk::frame_ms(passes));
  } else if (o.backend == "cpu") {
    const auto start = std::chrono::steady_clock::now();
    result = run_cpu(method, scene.color, scene.depth_m, scene.lens, options, default_cpu_threads(), &stats);
    fmt::print("  cpu frame {:9.3f} ms\n",
               std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  } else {
    throw std::invalid_argument("--backend must be gpu or cpu");
  }
  for (const auto& [key, value] : stats.items()) fmt::print("  {:<20} {}\n", key, value.dump());
  write_image(result, o.out_path);
  fmt::print("wrote {}\n", o.out_path);
  if (o.compare) write_comparison(scene, result, options.pattern.max_radius_px(), o);
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  auto* cmd = app.add_subcommand("render", "Render one image with one method");
  auto* scene = cmd->add_option("--scene", o->scene_name, "Procedural scene: hoops, pillars, points")
                    ->check(CLI::IsMember(procedural_scene_names()));
  auto* color = cmd->add_option("--color", o->color_path, "Colour image (linear RGB, e.g. EXR)")->check(CLI::ExistingFile);
  auto* depth = cmd->add_option("--depth", o->depth_path, "Depth image: planar view-space depth in metres, channel 0")
                    ->check(CLI::ExistingFile);
  color->needs(depth);
  depth->needs(color);
  scene->excludes(color);
  cmd->add_option("--width", o->width_px, "Procedural scene width in px")->check(CLI::Range(16, 16384));
  cmd->add_option("--height", o->height_px, "Procedural scene height in px")->check(CLI::Range(16, 16384));
  cmd->add_option("--lens", o->lens_path,
                  "Lens JSON: focal_length_mm, f_stop, sensor_width_mm, focus_distance_m [, coc_model]")
      ->check(CLI::ExistingFile);
  cmd->add_option("--fit-max-coc", o->fit_max_coc_px, "Set the f-stop so the scene's largest CoC radius is this many px");
  cmd->add_option("--method", o->method, "Filter method (`bokehbench methods` lists them)");
  cmd->add_option("--gather,-N", o->size_n, "Gather pattern size N (odd)");
  cmd->add_option("--spacing,-k", o->spacing_px, "Sample spacing k in px");
  cmd->add_option("--precision", o->precision, "Intermediate storage, e.g. FLAG layers f16 or f32 (default: the method's)");
  o->method_options.add_to(cmd);
  cmd->add_option("--buffer-scale", o->buffer_scale,
                  "Resolution divisor of the method's intermediates (FLAG: 3D buffer at 1/1, 1/2 or 1/4)");
  cmd->add_option("--backend", o->backend, "gpu (Vulkan) or cpu (reference)")->check(CLI::IsMember({"gpu", "cpu"}));
  cmd->add_option("--device", o->device, "Vulkan device index or name part (default: a GPU if present, else lavapipe)");
  cmd->add_option("--out", o->out_path, "Output image: .exr (linear) or .png (tone-mapped)");
  cmd->add_flag("--compare", o->compare,
                "Also report error vs the exact reference and write OUT_compare.png (reference, result, error map)");
  cmd->add_option("--reference-cache", o->reference_cache, "Directory caching the exact references");
  cmd->callback([o] { render(*o); });
}

}  // namespace bokeh
