// `bokehbench render`: one image through one method, so a user can look at what is being timed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "coc.hpp"
#include "image_io.hpp"
#include "parallel.hpp"
#include "commands.hpp"
#include "report.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct RenderOptions {
  AxisFlags axes;  // one value each; render() copies them into the fields below
  std::string scene_name;
  std::string color_path, depth_path, lens_path, method, precision, backend, device;
  std::string out_path = "render.png";
  int width_px = 0, height_px = 0, size_n = 0, spacing_px = 0;
  std::optional<double> fit_max_coc_px;
  MethodOptionFlags method_options;
  int buffer_scale = 0;
  bool compare = false;
  std::string reference_cache = "build/reference-cache";
  double max_buffer_mb = 0;
};

std::string comparison_sheet_path(const RenderOptions& o) {
  const std::filesystem::path out(o.out_path);
  return (out.parent_path() / (out.stem().string() + "_compare.png")).string();
}

// Beside OUT: OUT_compare.png with the exact reference, the result and an error heat map, so a
// person can see where a method fails (edges, highlights, large radii).
void write_comparison(const Scene& scene, const Image& result, float max_radius_px, const RenderOptions& o) {
  ExactReferenceCache cache(o.reference_cache);
  const ExactReferences refs = exact_references(scene, scene.lens, max_radius_px, cache);
  const nlohmann::json error = error_json(result, refs);
  fmt::print("  (interior: {} px in from every side, the largest CoC radius)\n", refs.interior_margin_px);
  for (const char* which : {"vs_energy_sum", "vs_depth_ordered", "vs_energy_sum_interior", "vs_depth_ordered_interior"}) {
    const auto& m = error[which];
    auto number = [&](const char* key, const char* format) {
      return m[key].is_null() ? std::string("n/a") : fmt::format(fmt::runtime(format), m[key].get<double>());
    };
    fmt::print("  {:<26} PSNR {:>8}  RMSE {}  max |err| {}  energy err {}  SSIM {}\n", which,
               psnr_text(m),
               number("rmse", "{:.4g}"), number("max_abs_error", "{:.4g}"),
               number("mean_relative_energy_error", "{:.2e}"), number("ssim", "{:.4f}"));
  }
  const std::string sheet_path = comparison_sheet_path(o);
  write_display_image(contact_sheet({{"exact scatter (energy sum)", to_display_srgb(refs.energy_sum)},
                                     {o.method + " (" + o.backend + ")", to_display_srgb(result)},
                                     {"|error| of luminance (99th pct = top)", error_heat_map(result, refs.energy_sum)}}),
                      sheet_path);
  fmt::print("wrote {}\n", sheet_path);
}

// Radii the pattern cannot hold are clamped to its largest radius, as a renderer clamps to its max
// CoC: the rule is documented (README, "Circle of confusion") and said here whenever it bites.
void warn_about_clamping(const Scene& scene, const GatherPattern& pattern, const RenderOptions& o) {
  const double widest = coc_scale_px(scene.lens, scene.depth_m.width) * max_defocus_ratio(scene.depth_m, scene.lens);
  if (o.fit_max_coc_px && widest == 0.0)
    fmt::print(stderr, "warning: --fit-max-coc {}: every depth lies at the focus distance, so no f-stop blurs this "
                       "scene; it stays sharp\n", *o.fit_max_coc_px);
  const float max_radius = pattern.max_radius_px();
  if (!(widest > max_radius * (1 + 1e-6))) return;
  const Image unclamped = coc_radius_image(scene.depth_m, scene.lens, std::numeric_limits<float>::max());
  const auto clamped = std::count_if(unclamped.pixels.begin(), unclamped.pixels.end(), [&](float r) { return r > max_radius; });
  fmt::print(stderr,
             "warning: CoC radii reach {:.4g} px{}, beyond the gather pattern's largest radius {} px (N={}, k={}): "
             "{} of {} pixels ({:.2g}%) are clamped to {} px\n",
             widest, o.fit_max_coc_px ? fmt::format(" (--fit-max-coc {})", *o.fit_max_coc_px) : std::string(),
             max_radius, pattern.size_n, pattern.spacing_px, clamped, unclamped.pixels.size(),
             100.0 * static_cast<double>(clamped) / static_cast<double>(unclamped.pixels.size()), max_radius);
}

// A highlight brighter than the method's intermediates hold saturates (or overflows to inf): said
// before the work, with the pixel, so it is never silent.
void warn_about_input_range(const Image& color, const Method& method, const FilterOptions& options) {
  if (!method.input_limit) return;
  const double limit = method.input_limit(options);
  std::size_t brightest = 0;
  for (std::size_t i = 0; i < color.pixels.size(); ++i)
    if (std::abs(color.pixels[i]) > std::abs(color.pixels[brightest])) brightest = i;
  const double value = color.pixels.empty() ? 0.0 : std::abs(color.pixels[brightest]);
  if (value <= limit) return;
  const std::size_t pixel = brightest / static_cast<std::size_t>(color.channels);
  fmt::print(stderr,
             "warning: the brightest colour, {:.4g} at pixel ({}, {}), is above what {} with {} intermediates holds "
             "unsaturated ({:.4g}): expect saturated or non-finite values there (see `bokehbench stability`)\n",
             value, pixel % color.width, pixel / color.width, method.name, options.precision, limit);
}

void render(RenderOptions& o) {
  // Everything given is checked before any work, the scene not yet built: method and options, output
  // paths, --fit-max-coc, the lens, the input files' headers, device limits and memory.
  o.axes.resolve();
  const GatherPattern pattern = o.axes.patterns().front();
  const Resolution frame = o.axes.frame_sizes().front();
  o.scene_name = o.axes.scenes.front();
  o.width_px = frame.width_px, o.height_px = frame.height_px;
  o.method = o.axes.methods.front();
  o.size_n = pattern.size_n, o.spacing_px = pattern.spacing_px;
  o.precision = o.axes.precisions.empty() ? "" : o.axes.precisions.front();
  o.buffer_scale = o.axes.scales.front();
  o.backend = o.axes.backends.front();
  const Method& method = find_method(o.method);
  FilterOptions options = method.defaults({o.size_n, o.spacing_px});
  if (!o.precision.empty()) options.precision = o.precision;
  options.buffer_scale = o.buffer_scale;
  for (const auto& [key, value] : o.method_options.values_for({o.method})) options.values[key] = value;
  std::optional<Lens> lens;
  if (!o.lens_path.empty()) lens = load_lens_json(o.lens_path);
  // The aperture: --aperture when given, else the lens file's, else the disc.
  options.aperture = o.axes.given(Axis::apertures) ? o.axes.aperture_shapes().front() : lens ? lens->aperture : Aperture{};
  check_options(method, options);
  check_image_extension(o.out_path);
  check_writable_file(o.out_path, {o.color_path, o.depth_path, o.lens_path});
  if (o.compare) check_writable_file(comparison_sheet_path(o), {o.color_path, o.depth_path, o.lens_path});
  if (o.fit_max_coc_px && !(std::isfinite(*o.fit_max_coc_px) && *o.fit_max_coc_px > 0))
    throw std::invalid_argument(fmt::format(
        "--fit-max-coc {} must be a finite number of pixels > 0 (the scene's largest CoC radius; for a sharp image "
        "use a lens file with a large f_stop)",
        *o.fit_max_coc_px));
  int width_px = o.width_px, height_px = o.height_px;
  if (!o.color_path.empty()) {
    const ImageFileInfo color = read_image_info(o.color_path), depth = read_image_info(o.depth_path);
    if (!depth.is_float)
      throw std::runtime_error(fmt::format("depth file '{}' stores {} values, not floats: depth must be float metres "
                                           "(e.g. EXR half or float), since integer pixels would be read as 0..1 m",
                                           o.depth_path, depth.pixel_type));
    if (!color.is_float)
      fmt::print(stderr, "warning: colour file '{}' stores {} values: read as linear values in [0, 1], without "
                         "decoding sRGB\n", o.color_path, color.pixel_type);
    width_px = color.width, height_px = color.height;
  }
  std::unique_ptr<vk::Context> ctx;
  if (o.backend == "gpu") ctx = std::make_unique<vk::Context>(o.device, method.needs(options));
  FramePlan plan;
  if (const std::string why = plan_frame(ctx.get(), method, options, width_px, height_px, o.max_buffer_mb, plan);
      !why.empty())
    throw std::runtime_error(fmt::format("{} ({}, {}) cannot render {}x{}: {}", o.method, options.precision, o.backend,
                                         width_px, height_px, why));

  Scene scene = o.color_path.empty() ? make_scene(o.scene_name, o.width_px, o.height_px)
                                     : load_scene(o.color_path, o.depth_path);
  if (lens) scene.lens = *lens;
  if (o.fit_max_coc_px) scene.lens = with_max_coc_radius(scene.lens, scene.depth_m, *o.fit_max_coc_px);
  scene.lens.aperture = options.aperture;
  check_depth(scene.depth_m);
  warn_about_clamping(scene, options.pattern, o);
  warn_about_input_range(scene.color, method, options);

  fmt::print("{} {}x{}, {} ({}) on {}, N={} k={} (max radius {} px), aperture {}, f/{:.3g} focus {} m\n", scene.name,
             scene.color.width, scene.color.height, o.method, options.precision, o.backend, o.size_n, o.spacing_px,
             options.pattern.max_radius_px(), options.aperture.name(),
             scene.lens.f_stop, scene.lens.focus_distance_m);
  Image result;
  nlohmann::json stats;
  if (ctx) {
    std::vector<vk::PassTime> passes;
    result = run_gpu(*ctx, method, scene.color, scene.depth_m, scene.lens, options, &passes, &stats);
    fmt::print("device: {} ({})\n", ctx->info().name, ctx->info().driver_info);
    for (const auto& p : passes) fmt::print("  {:<12} {:9.3f} ms\n", p.pass, p.ms);
    fmt::print("  {:<12} {:9.3f} ms (one frame after warm-up)\n", "frame", vk::frame_ms(passes));
  } else {
    const auto start = std::chrono::steady_clock::now();
    result = run_cpu(method, scene.color, scene.depth_m, scene.lens, options, default_cpu_threads(), &stats);
    fmt::print("  cpu frame {:9.3f} ms\n",
               std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  for (const auto& [key, value] : stats.items()) fmt::print("  {:<20} {}\n", key, value.dump());
  write_image(result, o.out_path);
  fmt::print("wrote {}\n", o.out_path);
  if (o.compare) write_comparison(scene, result, options.pattern.max_radius_px(), o);
  // Finite input, non-finite output: the method overflowed. Written anyway, so it can be looked at.
  if (const std::size_t bad = count_non_finite(result); bad > 0) {
    std::size_t first = 0;
    while (std::isfinite(result.pixels[first])) ++first;
    const std::size_t pixel = first / 3;
    throw std::runtime_error(fmt::format(
        "the result has {} non-finite values (inf/NaN; the first at pixel ({}, {})): {} ({}) overflowed on this input "
        "(written anyway to {}; see `bokehbench stability` for each method's safe range)",
        bad, pixel % result.width, pixel / result.width, o.method, options.precision, o.out_path));
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  auto* cmd = app.add_subcommand("render", "Render one image with one method");
  AxisFlags& a = o->axes;
  a.scenes = {"hoops"};
  a.resolutions = {"800x600"};
  a.methods = {"flag"};
  a.sizes = {"41"};
  a.scales = {1};
  a.backends = {"gpu"};  // precisions: empty, the method's own
  a.add_to(cmd, {}, {Axis::scenes, Axis::resolutions, Axis::methods, Axis::sizes, Axis::precisions, Axis::scales,
                     Axis::backends, Axis::apertures});
  CLI::Option* scene = a.option(Axis::scenes);
  auto* color = cmd->add_option("--color", o->color_path, "Colour image (linear RGB, e.g. EXR)")->check(CLI::ExistingFile);
  auto* depth = cmd->add_option("--depth", o->depth_path, "Depth image: planar view-space depth in metres, channel 0")
                    ->check(CLI::ExistingFile);
  color->needs(depth);
  depth->needs(color);
  scene->excludes(color);
  cmd->add_option("--lens", o->lens_path,
                  "Lens JSON: focal_length_mm, f_stop, sensor_width_mm, focus_distance_m [, coc_model] [, aperture: \"blades6\" "
                  "or {blades, rotation_deg, curvature}]")
      ->check(CLI::ExistingFile);
  // Checked in render() with the radius's own message (NaN and infinities included).
  cmd->add_option("--fit-max-coc", o->fit_max_coc_px, "Set the f-stop so the scene's largest CoC radius is this many px");
  o->method_options.add_to(cmd);
  cmd->add_option("--device", o->device, "Vulkan device index or name part (default: a GPU if present, else lavapipe)");
  cmd->add_option("--out", o->out_path, "Output image: .exr (linear) or .png (tone-mapped)");
  cmd->add_flag("--compare", o->compare,
                "Also report error vs the exact reference and write OUT_compare.png (reference, result, error map)");
  cmd->add_option("--reference-cache", o->reference_cache, "Directory caching the exact references");
  cmd->add_option("--max-buffer-mb", o->max_buffer_mb,
                  "Refuse (before building the scene) a configuration whose intermediates exceed this many MiB (0: no "
                  "limit; the device's and the host's memory are checked either way)")
      ->check(finite_number())
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([o] { render(*o); });
}

}  // namespace bokeh
