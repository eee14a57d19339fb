#pragma once
// A sweep's points made measurable: the Vulkan context (when a point runs on the GPU), each point's
// plan (why it cannot run, its work and memory model, known before anything is allocated), the
// scenes and lenses the points share, and the targets the runner times. Used by run_sweep (one
// run) and by a paired comparison's workers (paired.hpp), so both measure the same thing.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gpu_frame.hpp"
#include "runner.hpp"
#include "scene.hpp"
#include "sweep.hpp"
#include "vk/timestamps.hpp"

namespace bokeh {

// A method on the GPU: Vulkan timestamps after every pass.
class GpuTarget final : public runner::Target {
 public:
  GpuTarget(vk::Context& ctx, const Method& m, const Scene& scene, const Lens& lens, const FilterOptions& o);
  void warm_up() override;
  runner::Sample measure(int frames) override;
  std::uint64_t resident_bytes() const override;
  Image output() { return frame_.read_output(); }
  std::uint64_t intermediate_bytes() const { return filter_->intermediate_bytes(); }
  // One frame with the per-pass counters on (outside the timed samples).
  std::vector<vk::PassTime> counted_frame();
  nlohmann::json stats() { return filter_->stats(); }

 private:
  gpu::GpuFrame frame_;
  std::unique_ptr<gpu::GpuFilter> filter_;
  vk::TimestampQueries timer_;
  int passes_ = 16;
  double frame_estimate_s_ = 0;  // the warm-up's corner scaled to the frame: what the watchdog expects
};

// A method's CPU reference: wall clock of whole frames, CoC pass included.
class CpuTarget final : public runner::Target {
 public:
  CpuTarget(const Method& m, const Scene& scene, const Lens& lens, const FilterOptions& o, int threads);
  void warm_up() override;
  runner::Sample measure(int frames) override;
  const Image& output() const { return output_; }
  const nlohmann::json& stats() const { return stats_; }

 private:
  const Method& method_;
  const Scene& scene_;
  Lens lens_;
  FilterOptions options_;
  int threads_;
  Image output_;
  nlohmann::json stats_ = nlohmann::json::object();
};

// What is known of a point before anything of its size is allocated.
struct PointPlan {
  std::string skip;  // why it cannot run ("" when it can)
  nlohmann::json work = nlohmann::json::object(), memory = nlohmann::json::object();
};

// A lower bound on one frame's time, from the point's work model: its taps (every pass, the CoC pass
// included) at a ceiling rate, above what any measured method reaches. CPU (the references, and
// lavapipe, which runs on the CPU): 1e10 taps/s a thread, twice the fastest measured (naive's CPU
// gather, ~5e9 taps/s a thread on a 2.1 GHz EPYC with AVX2; results/README.md, "Every method at its best");
// a hardware GPU: 1e13 taps/s. `threads`: the CPU threads the point runs on.
struct FrameTimeFloor {
  double taps = 0, taps_per_s = 0, seconds = 0;
  std::string rate;  // how the rate was set, e.g. "1e10 taps/s a CPU thread x 2 threads"
};
FrameTimeFloor frame_time_floor(double taps, bool on_cpu, int threads);
// "" when the floor fits the budget; else why the point is skipped: "estimated at least 2.4 h for one
// frame (8.5e12 taps at <= 2e10 taps/s: 1e10 taps/s a CPU thread x 2 threads), over the budget of 300 s
// (--run-over-budget runs it anyway)".
std::string over_frame_budget(const FrameTimeFloor& floor, double budget_s);

class SweepTargets {
 public:
  // Opens the device when a point runs on the GPU (with what those points need) and plans every point.
  // frame_budget_s > 0: a point whose one frame is estimated above it is skipped, with the estimate
  // (frame_time_floor); 0: no time check.
  SweepTargets(const std::vector<SweepPoint>& points, const std::string& device, int cpu_threads, double max_buffer_mb,
               double frame_budget_s = 0);
  const std::vector<PointPlan>& plans() const { return plans_; }
  vk::Context* context() { return ctx_ ? &*ctx_ : nullptr; }
  int cpu_threads() const { return threads_; }
  const Scene& scene(const SweepPoint& p);
  const Scene& scene(const std::string& name, const Resolution& resolution);  // made once, then shared
  Lens lens(const SweepPoint& p);  // the scene's lens with the point's largest CoC
  std::unique_ptr<runner::Target> prepare(std::size_t i);

 private:
  const std::vector<SweepPoint>& points_;
  std::optional<vk::Context> ctx_;
  int threads_ = 1;
  std::vector<PointPlan> plans_;
  std::map<std::string, Scene> scenes_;
};

}  // namespace bokeh
