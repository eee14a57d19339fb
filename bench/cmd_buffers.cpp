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
  AxisFlags axes;
  std::vector<double> budget_lines_mib = {64, 16};
  SweepFlags sweep;
};

double allocated_mib(const nlohmann::json& point) { return point["memory"]["bytes"].get<double>() / (1024.0 * 1024.0); }

void buffers(BuffersOptions& o) {
  o.axes.resolve(&o.sweep);
  const Method& flag = find_method("flag");
  Axes axes;
  axes.methods = {flag.name};
  axes.scenes = o.axes.scenes;
  axes.resolutions = o.axes.frame_sizes();
  axes.patterns = o.axes.patterns();
  for (const auto& p : o.axes.precisions) layer_precision_from_string(p);
  axes.precisions = o.axes.precisions.empty() ? std::vector<std::string>{"all"} : o.axes.precisions;
  for (int s : o.axes.scales)
    if (std::find(flag.buffer_scales.begin(), flag.buffer_scales.end(), s) == flag.buffer_scales.end())
      throw std::invalid_argument(fmt::format("--scales: FLAG has no buffer scale {} (it has {})", s,
                                              fmt::join(flag.buffer_scales, ", ")));
  axes.scales = o.axes.scales.empty() ? std::vector<int>{0} : o.axes.scales;
  std::vector<int> sizes;
  for (const auto& p : axes.patterns) sizes.push_back(p.size_n);

  SweepSettings s = o.sweep.settings("buffers", "plot_buffers.py");
  s.config = {{"scene", axes.scenes.front()},
              {"resolutions", o.axes.resolutions},
              {"sizes", sizes},
              {"patterns", o.axes.sizes},
              {"spacing_px", o.axes.spacing_px},
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
        "flag_f32", fmt::format("{}/{}x{}", p.resolution.text(), p.options.pattern.size_n, p.options.pattern.spacing_px), [&scene, lens, p, threads] {
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
  o.sweep.apply_shard(axes);
  run_sweep(expand(axes), s);
}

}  // namespace

void add_buffers_command(CLI::App& app) {
  auto o = std::make_shared<BuffersOptions>();
  auto* cmd = app.add_subcommand(
      "buffers", "FLAG 3D buffer at reduced precision and resolution: memory, GPU time and error side by side");
  AxisFlags& a = o->axes;
  a.resolutions = {"800x600", "1280x720", "1920x1080", "3840x2160"};
  a.sizes = {"21", "41"};
  a.scenes = {"hoops"};  // precisions and scales: every one FLAG has
  a.add_to(cmd, {Axis::resolutions, Axis::sizes, Axis::precisions, Axis::scales}, {Axis::scenes});
  cmd->add_option("--budget-lines", o->budget_lines_mib, "Memory budgets (MiB) to report and draw")
      ->check(finite_number())
      ->check(CLI::PositiveNumber);
  o->sweep.add_to(cmd, 240, 512);
  a.add_quick(cmd, "Small sweep for CI and tests (160x120, N = 9 and 13)",
              {{Axis::resolutions, {"160x120"}}, {Axis::sizes, {"9", "13"}}}, 12);
  cmd->callback([o] { buffers(*o); });
}

}  // namespace bokeh
