// `bokehbench buffers`: FLAG's 3D buffer at reduced precision and reduced resolution (the paper's
// section 5: "Half resolution or quarter resolution 3D buffers could be used ... Further memory could
// be saved by decreasing the precision"): memory, GPU frame time and error side by side, over
// resolution x gather size x layer precision x buffer scale, measured interleaved. --methods takes any
// other method that declares buffer scales (a package's manifest buffer_scales) in FLAG's place or
// beside it. Each FLAG point's error
// is reported against full-resolution f32 FLAG of the same scene (error.vs_flag_f32, CPU, computed in
// strips once per resolution and size) and against the exact scatter (error.vs_energy_sum): full-res
// FLAG carries the pattern of its k-px sample grid, which the reduced pipelines, sampling an s x s
// box-filtered image, do not reproduce, so "error vs full-res FLAG" alone overstates how much worse
// they look. Points whose buffers exceed --max-buffer-mb are skipped unallocated: lavapipe reports a
// heap but does not enforce it. Beside the full, half and quarter buffers, the streamed layers
// (layer_buffer = streamed, kernels/flag/flag_gpu.hpp) at full resolution, one point per --band-rows.
#include <map>
#include <set>
#include <vector>

#include <fmt/format.h>

#include "accuracy.hpp"
#include "commands.hpp"
#include "flag.hpp"
#include "intervals.hpp"
#include "report.hpp"
#include "run.hpp"
#include "scene.hpp"
#include "sweep.hpp"

namespace bokeh {

namespace {

struct BuffersOptions {
  AxisFlags axes;
  std::vector<double> budget_lines_mib = {64, 16};
  std::vector<int> band_rows = {0};  // FLAG's streamed points, one per band height (0: the device's auto)
  SweepFlags sweep;
};

double allocated_mib(const nlohmann::json& point) { return point["memory"]["bytes"].get<double>() / (1024.0 * 1024.0); }

bool is_streamed(const nlohmann::json& point) {
  return point.contains("options") && point["options"].value("layer_buffer", "") == "streamed";
}

// The full buffer at every other option's default (written "" before auto became the default).
bool is_full_buffer(const nlohmann::json& point) {
  return point["variant"] == "" || point["variant"] == "/layer_buffer:\"full\"";
}

// The frame of the same resolution, N, k and precision a point is compared with: its streamed and
// full-resolution buffers are visited back to back in every round (visit_together).
std::string frame_key(const nlohmann::json& p) {
  return fmt::format("{}x{}/N:{}/k:{}/{}", p["width_px"].get<int>(), p["height_px"].get<int>(), p["N"].get<int>(),
                     p["k"].get<int>(), p["precision"].get<std::string>());
}

// Streamed over full-buffer frame time: the median of the ratios of the rounds in which both took a
// sample (each round's two samples are adjacent in time: a drifting machine moves both), with its 95%
// interval (intervals.hpp).
nlohmann::json streamed_vs_full(const nlohmann::json& streamed, const nlohmann::json& full) {
  const RoundValues streamed_ms = round_values(streamed), full_ms = round_values(full);
  const std::optional<Interval> ratio = paired_ratio_interval(streamed_ms, full_ms);
  if (!ratio) return nullptr;
  std::size_t rounds = 0;
  for (const auto& [round, ms] : streamed_ms) rounds += full_ms.count(round);
  return {{"frame_ms_ratio_median", ratio->estimate}, {"low", ratio->low}, {"high", ratio->high}, {"rounds", rounds}};
}

// The methods swept: each must declare a reduced buffer scale (else there is nothing to measure) and
// every scale --scales names.
std::vector<const Method*> buffer_methods(const AxisFlags& a) {
  std::vector<const Method*> methods;
  for (const auto& name : a.methods) {
    const Method& m = find_method(name);
    if (m.buffer_scales.size() < 2)
      throw std::invalid_argument(fmt::format(
          "buffers: {} has one buffer scale ({}): nothing reduced to measure (a package declares buffer_scales in its "
          "manifest)", m.name, fmt::join(m.buffer_scales, ", ")));
    for (int s : a.scales)
      if (std::find(m.buffer_scales.begin(), m.buffer_scales.end(), s) == m.buffer_scales.end())
        throw std::invalid_argument(fmt::format("--scales: {} has no buffer scale {} (it has {})", m.name, s,
                                                fmt::join(m.buffer_scales, ", ")));
    methods.push_back(&m);
  }
  return methods;
}

void buffers(BuffersOptions& o) {
  o.axes.resolve(&o.sweep);
  const std::vector<const Method*> methods = buffer_methods(o.axes);
  const bool has_flag = std::any_of(methods.begin(), methods.end(), [](const Method* m) { return m->name == "flag"; });
  Axes axes;
  for (const Method* m : methods) axes.methods.push_back(m->name);
  axes.scenes = o.axes.scenes;
  axes.resolutions = o.axes.frame_sizes();
  axes.patterns = o.axes.patterns();
  if (has_flag)
    for (const auto& p : o.axes.precisions) layer_precision_from_string(p);
  axes.precisions = o.axes.precisions.empty() ? std::vector<std::string>{"all"} : o.axes.precisions;
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
              {"methods", axes.methods},
              {"error_reference", "error.vs_energy_sum: the exact scatter, every point; error.vs_flag_f32 (FLAG's "
                                  "points): CPU FLAG with f32 layers at full resolution, same scene, lens, N and k "
                                  "(flag_blur: no layer buffer at any size)"},
              {"band_rows", o.band_rows},
              {"streamed", "layer_buffer = streamed points: full resolution, each precision, one per band_rows (0: "
                           "auto); memory.details.streamed has the band and ring rows"}};
  const int threads = o.sweep.cpu_threads;
  s.extra_reference = [threads](const SweepPoint& p, const Scene& scene,
                                const Lens& lens) -> std::optional<SweepSettings::ExtraReference> {
    if (p.method->name != "flag") return std::nullopt;
    return SweepSettings::ExtraReference{
        "flag_f32", fmt::format("{}/{}x{}", p.resolution.text(), p.options.pattern.size_n, p.options.pattern.spacing_px), [&scene, lens, p, threads] {
          const CocInput coc = cpu_coc_pass(scene.color, scene.depth_m, lens, p.options.pattern);
          return flag_blur(coc.packed, p.options.pattern, LayerPrecision::f32, threads > 0 ? threads : default_cpu_threads());
        }};
  };
  s.visit_together = [](const SweepPoint& p) {
    return fmt::format("{}/N:{}/k:{}/{}", p.resolution.text(), p.options.pattern.size_n, p.options.pattern.spacing_px,
                       p.options.precision);
  };
  const std::vector<double> lines = o.budget_lines_mib;
  s.derive = derive_buffers;  // reads the budget lines from config (as merge does)
  s.summary = [lines](const nlohmann::json& doc) {
    // Every point (and every skip) by frame: the memory / time / accuracy trade in one table.
    fmt::print("\n{:<66} {:>10} {:>24} {:>9} {:>10}  {}\n", "point", "MiB", "frame ms [95%]", "PSNR", "vs FLAG f32",
               "streamed/full [95%]");
    for (const auto& p : doc["points"]) {
      std::string ratio;
      if (p.contains("streamed_vs_full") && !p["streamed_vs_full"].is_null())
        ratio = fmt::format("{:.2f}x [{:.2f}-{:.2f}] ({} rounds)", p["streamed_vs_full"]["frame_ms_ratio_median"].get<double>(),
                            p["streamed_vs_full"]["low"].get<double>(), p["streamed_vs_full"]["high"].get<double>(),
                            p["streamed_vs_full"]["rounds"].get<int>());
      fmt::print("{:<66} {:>10.2f} {:>24} {:>9} {:>10}  {}\n", p["id"].get<std::string>(), allocated_mib(p),
                 interval_text(p["frame_ms_interval"], 2), psnr_text(p["error"]["vs_energy_sum"]),
                 psnr_text(p["error"].value("vs_flag_f32", nlohmann::json())), ratio);
    }
    for (const auto& sk : doc["skipped"])
      fmt::print("{:<66} skipped: {}\n", sk.value("id", std::string("?")), sk.value("reason", std::string()));
    for (double mib : lines) {
      fmt::print("\nWithin {} MiB of buffers (fastest first):\n", mib);
      std::vector<const nlohmann::json*> fit;
      for (const auto& p : doc["points"])
        if (allocated_mib(p) <= mib) fit.push_back(&p);
      std::sort(fit.begin(), fit.end(), [](auto* a, auto* b) {
        return (*a)["frame_ms"]["median"].template get<double>() < (*b)["frame_ms"]["median"].template get<double>();
      });
      for (const auto* p : fit)
        fmt::print("  {:<58} {:8.2f} MiB  frame {} ms (filter passes {:8.2f})  PSNR {}{}\n",
                   (*p)["id"].get<std::string>(), allocated_mib(*p), interval_text((*p)["frame_ms_interval"], 2),
                   (*p)["filter_passes_ms"].get<double>(), psnr_text((*p)["error"]["vs_energy_sum"]),
                   (*p)["error"].contains("vs_flag_f32")
                       ? fmt::format(" (vs f32 FLAG {})", psnr_text((*p)["error"]["vs_flag_f32"]))
                       : std::string());
    }
  };
  flag_through_its_buffer(axes);  // the subject here
  o.sweep.apply_shard(axes);
  std::vector<SweepPoint> points = expand(axes);
  if (!has_flag) {
    run_sweep(points, s);
    return;
  }
  // The streamed layers at full resolution, beside the full and reduced buffers, in the shard of the
  // full buffer they are compared with (streamed_vs_full).
  std::set<std::string> shard_keys;
  for (const auto& p : points) shard_keys.insert(shard_key(p.id, p.method->name, p.variant));
  const Method& flag = find_method("flag");
  const double streamed = flag.option("layer_buffer")->parse("streamed");
  for (int rows : o.band_rows) {
    Axes banded = axes;
    banded.methods = {flag.name};
    banded.scales = {1};
    banded.shard_index = banded.shard_count = 1;
    banded.option_values = {{"layer_buffer", streamed}, {"band_rows", rows}};
    for (auto& p : expand(banded))
      if (shard_keys.count(shard_key(p.id, p.method->name, p.variant))) points.push_back(std::move(p));
  }
  run_sweep(points, s);
}

}  // namespace

void derive_buffers(nlohmann::json& doc) {
  const std::vector<double> lines = doc.at("config").at("budget_lines_mib").get<std::vector<double>>();
  for (auto& p : doc["points"]) {
    if (!is_streamed(p)) continue;
    for (const auto& full : doc["points"])
      if (!is_streamed(full) && full["buffer_scale"] == 1 && is_full_buffer(full) && frame_key(full) == frame_key(p))
        p["streamed_vs_full"] = streamed_vs_full(p, full);
  }
  for (auto& p : doc["points"]) {
    p["fits_mib"] = nlohmann::json::array();
    for (double mib : lines)
      if (allocated_mib(p) <= mib) p["fits_mib"].push_back(mib);
    double filter_ms = 0;  // the CoC pass is the same for every configuration of a resolution and N
    for (const auto& [pass, ms] : p["pass_ms"].items())
      if (pass != "coc") filter_ms += ms.get<double>();
    p["filter_passes_ms"] = filter_ms;
  }
}

void add_buffers_command(CLI::App& app) {
  auto o = std::make_shared<BuffersOptions>();
  auto* cmd = app.add_subcommand(
      "buffers", "FLAG 3D buffer (or a method package's declared buffer_scales) at reduced precision and resolution: "
                 "memory, GPU time and error side by side");
  AxisFlags& a = o->axes;
  a.resolutions = {"800x600", "1280x720", "1920x1080", "3840x2160"};
  a.sizes = {"21", "41"};
  a.scenes = {"hoops"};  // precisions and scales: every one each method has
  a.methods = {"flag"};
  a.add_to(cmd, {Axis::resolutions, Axis::sizes, Axis::precisions, Axis::scales, Axis::methods}, {Axis::scenes});
  cmd->add_option("--budget-lines", o->budget_lines_mib, "Memory budgets (MiB) to report and draw")
      ->check(finite_number())
      ->check(CLI::PositiveNumber);
  cmd->add_option("--band-rows", o->band_rows,
                  "Streamed layers: output rows per band, one point per value at full resolution (0: the device's "
                  "auto, flag_gpu.hpp)")
      ->check(CLI::Range(0, 1 << 16));
  o->sweep.add_to(cmd, 240, 512);
  a.add_quick(cmd, "Small sweep for CI and tests (160x120, N = 9 and 13)",
              {{Axis::resolutions, {"160x120"}}, {Axis::sizes, {"9", "13"}}}, 12);
  cmd->callback([o] { buffers(*o); });
}

}  // namespace bokeh
