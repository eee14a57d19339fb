#include "targets.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>

#include <fmt/format.h>

#include "coc.hpp"
#include "parallel.hpp"
#include "run.hpp"

namespace bokeh {

GpuTarget::GpuTarget(vk::Context& ctx, const Method& m, const Scene& scene, const Lens& lens, const FilterOptions& o)
    : frame_(ctx, scene.color, scene.depth_m, lens, o.pattern), filter_(m.make_gpu(frame_, o)), timer_(ctx) {}

void GpuTarget::warm_up() {
  gpu::warm_up(frame_, *filter_, timer_);  // lavapipe compiles each pipeline here, at its first use
  const auto start = std::chrono::steady_clock::now();
  gpu::warm_up(frame_, *filter_, timer_);
  const double corner_px = std::min(frame_.width(), 16u) * std::min(frame_.height(), 16u);
  frame_estimate_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() *
                      frame_.width() * frame_.height() / corner_px;
}

runner::Sample GpuTarget::measure(int frames) {
  frame_.ctx.watchdog_expected_s = frames * frame_estimate_s_;
  timer_.reserve(static_cast<std::uint32_t>(frames * passes_ + 2));
  const auto passes = gpu::run_frames(frame_, *filter_, timer_, frames);
  passes_ = static_cast<int>(passes.size());
  runner::Sample s{vk::frame_ms(passes), {}};
  for (const auto& p : passes) s.pass_ms[p.pass] = p.ms;
  return s;
}

std::uint64_t GpuTarget::resident_bytes() const {
  return 4ull * frame_.width() * frame_.height() * 16 + filter_->intermediate_bytes();
}

std::vector<vk::PassTime> GpuTarget::counted_frame() {
  frame_.ctx.watchdog_expected_s = frame_estimate_s_;
  timer_.count_invocations(true);
  auto passes = gpu::run_frames(frame_, *filter_, timer_, 1);
  timer_.count_invocations(false);
  return passes;
}

CpuTarget::CpuTarget(const Method& m, const Scene& scene, const Lens& lens, const FilterOptions& o, int threads)
    : method_(m), scene_(scene), lens_(lens), options_(o), threads_(threads) {}

void CpuTarget::warm_up() { output_ = run_cpu(method_, scene_.color, scene_.depth_m, lens_, options_, threads_, &stats_); }

runner::Sample CpuTarget::measure(int frames) {
  const auto start = std::chrono::steady_clock::now();
  for (int f = 0; f < frames; ++f)
    output_ = run_cpu(method_, scene_.color, scene_.depth_m, lens_, options_, threads_, &stats_);
  return {std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / frames, {}};
}

namespace {

nlohmann::json work_json(const std::vector<PassWork>& passes, double pixels) {
  nlohmann::json out = nlohmann::json::object();
  double taps = 0;
  for (const auto& p : passes) {
    out["passes"][p.pass] = {{"taps", p.taps}, {"bytes_read", p.bytes_read}, {"bytes_written", p.bytes_written}};
    if (p.bytes_kept > 0) out["passes"][p.pass]["bytes_kept"] = p.bytes_kept;
    taps += p.taps;
  }
  out["taps"] = taps;
  out["taps_per_pixel"] = taps / pixels;
  return out;
}

constexpr double kCpuTapsPerThreadCeiling = 1e10;
constexpr double kGpuTapsCeiling = 1e13;

std::string duration_words(double s) {
  if (s < 120) return fmt::format("{:.0f} s", s);
  if (s < 7200) return fmt::format("{:.1f} min", s / 60);
  if (s < 2 * 86400) return fmt::format("{:.1f} h", s / 3600);
  return fmt::format("{:.1f} days", s / 86400);
}

// 1.1e13, 2e10: the exponent without '+' and leading zeros.
std::string sci(double v) {
  std::string text = fmt::format("{:.2g}", v);
  const auto e = text.find('e');
  if (e == std::string::npos) return text;
  std::string exponent = text.substr(e + 1);
  const bool negative = exponent[0] == '-';
  exponent.erase(0, exponent.find_first_not_of("+-0"));
  return text.substr(0, e) + "e" + (negative ? "-" : "") + exponent;
}

// The threads lavapipe runs a dispatch on: LP_NUM_THREADS when set, else every core.
int lavapipe_threads() {
  if (const char* env = std::getenv("LP_NUM_THREADS"); env && std::atoi(env) > 0) return std::atoi(env);
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace

FrameTimeFloor frame_time_floor(double taps, bool on_cpu, int threads) {
  FrameTimeFloor f;
  f.taps = taps;
  if (on_cpu) {
    f.taps_per_s = kCpuTapsPerThreadCeiling * std::max(1, threads);
    f.rate = fmt::format("{} taps/s a CPU thread x {} thread{}", sci(kCpuTapsPerThreadCeiling), threads,
                         threads == 1 ? "" : "s");
  } else {
    f.taps_per_s = kGpuTapsCeiling;
    f.rate = fmt::format("{} taps/s, above any GPU's gather", sci(kGpuTapsCeiling));
  }
  f.seconds = taps / f.taps_per_s;
  return f;
}

std::string over_frame_budget(const FrameTimeFloor& floor, double budget_s) {
  if (!(budget_s > 0) || floor.seconds <= budget_s) return {};
  return fmt::format("estimated at least {} for one frame ({} taps at <= {} taps/s: {}), over the budget of {} s "
                     "(--run-over-budget runs it anyway)",
                     duration_words(floor.seconds), sci(floor.taps), sci(floor.taps_per_s), floor.rate, budget_s);
}

SweepTargets::SweepTargets(const std::vector<SweepPoint>& points, const std::string& device, int cpu_threads,
                           double max_buffer_mb, double frame_budget_s)
    : points_(points), threads_(cpu_threads > 0 ? cpu_threads : default_cpu_threads()), plans_(points.size()) {
  if (const auto wanted = gpu_requirements(points)) ctx_.emplace(device, *wanted);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SweepPoint& p = points[i];
    const Method& m = *p.method;
    const int w = p.resolution.width_px, h = p.resolution.height_px;
    try {
      check_options(m, p.options);
      std::vector<PassWork> work = {gpu::coc_pass_work(p.options.pattern, w, h)};
      const auto& model = p.backend == "cpu" && m.cpu_work ? m.cpu_work : m.work;
      const bool on_gpu = p.backend == "gpu" && context();
      const FilterOptions as_run = on_gpu && m.on_device ? m.on_device(p.options, &context()->info()) : p.options;
      for (auto& pass : model(as_run, w, h)) work.push_back(std::move(pass));
      plans_[i].work = work_json(work, static_cast<double>(w) * h);
      // What an auto choice became on this device, beside the point's options as given (its id).
      if (const auto run = m.options_json(as_run); run != m.options_json(p.options)) plans_[i].work["options_as_run"] = run;
      // Device features and limits, memory budget, host memory: known before anything is allocated.
      FramePlan plan;
      plans_[i].skip = plan_frame(p.backend == "gpu" ? context() : nullptr, m, p.options, w, h, max_buffer_mb, plan);
      const MemoryUse& use = plan.intermediates;
      if (plan.sized) plans_[i].memory = {{"bytes", use.bytes}, {"from_driver", use.from_driver}};
      if (plan.sized && p.backend == "gpu") plans_[i].memory["details"] = use.details;
      // Time: a frame that cannot fit the budget even at a ceiling rate is said up front, never started.
      if (plans_[i].skip.empty() && frame_budget_s > 0) {
        const bool on_cpu = p.backend == "cpu" || (context() && context()->info().is_software());
        const int threads = p.backend == "cpu" ? threads_ : lavapipe_threads();
        plans_[i].skip =
            over_frame_budget(frame_time_floor(plans_[i].work["taps"].get<double>(), on_cpu, threads), frame_budget_s);
      }
    } catch (const std::exception& e) {
      plans_[i].skip = e.what();
    }
  }
}

const Scene& SweepTargets::scene(const SweepPoint& p) { return scene(p.scene, p.resolution); }

const Scene& SweepTargets::scene(const std::string& name, const Resolution& resolution) {
  const std::string key = name + "/" + resolution.text();
  auto it = scenes_.find(key);
  if (it == scenes_.end()) it = scenes_.emplace(key, make_scene(name, resolution.width_px, resolution.height_px)).first;
  return it->second;
}

Lens SweepTargets::lens(const SweepPoint& p) {
  const Scene& s = scene(p);
  Lens lens = with_max_coc_radius(s.lens, s.depth_m, p.max_coc_px);
  lens.aperture = p.options.aperture;
  return lens;
}

std::unique_ptr<runner::Target> SweepTargets::prepare(std::size_t i) {
  const SweepPoint& p = points_.at(i);
  if (p.backend == "gpu") return std::make_unique<GpuTarget>(*ctx_, *p.method, scene(p), lens(p), p.options);
  return std::make_unique<CpuTarget>(*p.method, scene(p), lens(p), p.options, threads_);
}

}  // namespace bokeh
