// `bokehbench buffers`: FLAG's 3D buffer at reduced precision and reduced resolution (the paper's
// section 5: "Half resolution or quarter resolution 3D buffers could be used ... Further memory could
// be saved by decreasing the precision"): memory, GPU frame time and error side by side, over
// resolution x gather size x layer precision x buffer scale, measured interleaved. Each point's error
// is reported against full-resolution f32 FLAG of the same scene (error.vs_flag_f32, CPU, computed in
// strips once per resolution and size) and against the exact scatter (error.vs_energy_sum): full-res
// FLAG carries the pattern of its k-px sample grid, which the reduced pipelines, sampling an s x s
// box-filtered image, do not reproduce, so "error vs full-res FLAG" alone overstates how much worse
// they look. Points whose buffers exceed --max-buffer-mb are skipped unallocated: lavapipe reports a
// heap but does not enforce it.
#include <fmt/format.h>

#include "accuracy.hpp"
#include "commands.hpp"
#include "flag.hpp"
#include "report.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct BuffersOptions {
  std::vector<std::string> resolutions = {"800x600", "1280x720", "1920x1080", "3840x2160"};
  std::vector<int> sizes = {21, 41};
  int spacing_px = 2;
  std::vector<std::string> precisions;  // default: every precision FLAG has
  std::vector<int> scales;              // default: every scale FLAG has
  std::vector<double> budget_lines_mib = {64, 16};
  std::string scene = "hoops";
  SweepFlags sweep;
  bool quick = false;
  CLI::Option *resolutions_opt = nullptr, *sizes_opt = nullptr, *budget_opt = nullptr;
};

double allocated_mib(const nlohmann::json& point) { return point["memory"]["bytes"].get<double>() / (1024.0 * 1024.0); }

void buffers(BuffersOptions& o) {
  if (o.quick) {
    if (!given(o.resolutions_opt)) o.resolutions = {"160x120"};
    if (!given(o.sizes_opt)) o.sizes = {9, 13};
    if (!given(o.budget_opt)) o.sweep.budget_s = 12;
  }
  const Method& flag = find_method("flag");
  Axes axes;
  axes.methods = {flag.name};
  axes.scenes = {o.scene};
  axes.resolutions.clear();
  for (const auto& r : o.resolutions) axes.resolutions.push_back(parse_resolution(r));
  for (int n : o.sizes) {
    axes.patterns.push_back({n, o.spacing_px});
    validate(axes.patterns.back());
  }
  for (const auto& p : o.precisions) layer_precision_from_string(p);
  axes.precisions = o.precisions.empty() ? std::vector<std::string>{"all"} : o.precisions;
  for (int s : o.scales)
    if (std::find(flag.buffer_scales.begin(), flag.buffer_scales.end(), s) == flag.buffer_scales.end())
      throw std::invalid_argument(fmt::format("--scales: FLAG has no buffer scale {} (it has {})", s,
                                              fmt::join(flag.buffer_scales, ", ")));
  axes.scales = o.scales.empty() ? std::vector<int>{0} : o.scales;

  SweepSettings s = o.sweep.settings("buffers", "plot_buffers.py");
  s.config = {{"scene", o.scene},
              {"resolutions", o.resolutions},
              {"sizes", o.sizes},
              {"spacing_px", o.spacing_px},
              {"max_buffer_mb", o.sweep.max_buffer_mb},
              {"budget_lines_mib", o.budget_lines_mib},
              {"scene_coc", "lens f-stop set per N so the scene's largest CoC radius equals k (N - 1) / 2"},
              {"memory", "memory.details.paper_convention_bytes = W*H*ceil(N/2)*bytes_per_texel/scale^3 (the paper's "
                         "332/42/5.2 MB for f16); memory.details.layer_buffer_bytes = vkGetImageMemoryRequirements of "
                         "the ceil(W/s) x ceil(H/s) x ceil(ceil(N/2)/s) 3D image; memory.bytes adds the bracket and "
                         "low-res buffers: what --max-buffer-mb is checked against"},
              {"error_reference", "error.vs_flag_f32: CPU FLAG with f32 layers at full resolution, same scene, lens, N "
                                  "and k (flag_blur_in_strips, bit for bit flag_blur)"}};
  const int threads = o.sweep.cpu_threads;
  s.extra_reference = [threads](const SweepPoint& p, const Scene& scene,
                                const Lens& lens) -> std::optional<SweepSettings::ExtraReference> {
    return SweepSettings::ExtraReference{
        "flag_f32", fmt::format("{}/{}", p.resolution.text(), p.options.pattern.size_n), [&scene, lens, p, threads] {
          const CocInput coc = cpu_coc_pass(scene.color, scene.depth_m, lens, p.options.pattern);
          return flag_blur_in_strips(coc.packed, p.options.pattern, LayerPrecision::f32, 256,
                                     threads > 0 ? threads : default_cpu_threads());
        }};
  };
  const std::vector<double> lines = o.budget_lines_mib;
  s.derive = [lines](nlohmann::json& doc) {
    for (auto& p : doc["points"]) {
      p["fits_mib"] = nlohmann::json::array();
      for (double mib : lines)
        if (allocated_mib(p) <= mib) p["fits_mib"].push_back(mib);
      double flag_ms = 0;  // the CoC pass is the same for every configuration of a resolution and N
      for (const auto& [pass, ms] : p["pass_ms"].items())
        if (pass != "coc") flag_ms += ms.get<double>();
      p["flag_passes_ms"] = flag_ms;
    }
  };
  s.summary = [lines](const nlohmann::json& doc) {
    for (double mib : lines) {
      fmt::print("\nWithin {} MiB of FLAG buffers (fastest first):\n", mib);
      std::vector<const nlohmann::json*> fit;
      for (const auto& p : doc["points"])
        if (allocated_mib(p) <= mib) fit.push_back(&p);
      std::sort(fit.begin(), fit.end(), [](auto* a, auto* b) {
        return (*a)["frame_ms"]["median"].template get<double>() < (*b)["frame_ms"]["median"].template get<double>();
      });
      for (const auto* p : fit)
        fmt::print("  {:<58} {:8.2f} MiB  frame {:9.2f} ms (FLAG passes {:8.2f})  PSNR vs f32 FLAG {}\n",
                   (*p)["id"].get<std::string>(), allocated_mib(*p), (*p)["frame_ms"]["median"].get<double>(),
                   (*p)["flag_passes_ms"].get<double>(), psnr_text((*p)["error"]["vs_flag_f32"]));
    }
  };
  run_sweep(expand(axes), s);
}

}  // namespace

void add_buffers_command(CLI::App& app) {
  auto o = std::make_shared<BuffersOptions>();
  auto* cmd = app.add_subcommand(
      "buffers", "FLAG 3D buffer at reduced precision and resolution: memory, GPU time and error side by side");
  o->resolutions_opt = cmd->add_option("--resolutions", o->resolutions, "Frame sizes WIDTHxHEIGHT");
  o->sizes_opt = cmd->add_option("--sizes", o->sizes, "Gather sizes N (odd)");
  cmd->add_option("--spacing,-k", o->spacing_px, "Sample spacing k in px");
  cmd->add_option("--precisions", o->precisions, "3D-buffer precisions (default: all FLAG has)");
  cmd->add_option("--scales", o->scales, "Buffer scales (default: all FLAG has: 1 full, 2 half, 4 quarter)");
  cmd->add_option("--budget-lines", o->budget_lines_mib, "Memory budgets (MiB) to report and draw")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--scene", o->scene, "Procedural scene")->check(CLI::IsMember(procedural_scene_names()));
  o->sweep.add_to(cmd, 240, 512);
  o->budget_opt = cmd->get_option("--budget-s");
  cmd->add_flag("--quick", o->quick, "Small sweep for CI and tests (160x120, N = 9 and 13)");
  cmd->callback([o] { buffers(*o); });
}

}  // namespace bokeh
