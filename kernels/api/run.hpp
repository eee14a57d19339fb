#pragma once
// scene (colour + depth) -> circle of confusion -> filter passes, once, on the CPU or the GPU.
#include <vector>

#include "method.hpp"
#include "vk/context.hpp"
#include "vk/timestamps.hpp"

namespace bokeh {

struct CocInput {
  Image radius_px;  // clamped to the pattern's max radius
  Image packed;     // (rgb / discrete disc area, radius)
};
// Also checks the colour (check_color) and depth before any work.
CocInput cpu_coc_pass(const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern,
                      int threads = default_cpu_threads());

// The CPU reference, CoC pass included. `stats` receives what it found (CpuInput::stats) if given.
Image run_cpu(const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, int threads, nlohmann::json* stats = nullptr);

// One GPU frame (warmed up first). `pass_times` receives per-pass milliseconds and `stats` the
// frame's statistics (GpuFilter::stats) if given.
Image run_gpu(vk::Context& ctx, const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, std::vector<vk::PassTime>* pass_times = nullptr,
              nlohmann::json* stats = nullptr);

// What one frame at width x height needs, known before anything of that size is allocated.
struct FramePlan {
  bool sized = false;            // false: refused before the sizes below were worked out
  MemoryUse intermediates;       // the method's own (gpu_memory or cpu_memory_bytes): what budgets bound
  std::uint64_t device_bytes = 0;  // GPU: the frame's shared buffers plus the intermediates
  std::uint64_t host_bytes = 0;    // the images on the host (and the CPU reference's intermediates)
};

// Why `method` cannot run one frame at width x height on `ctx` (null: as its CPU reference), in words
// ("" when it can), fills `plan` either way. Checked in order: the method's own limits
// (Method::unsupported), the device's features, the frame's storage buffers against
// maxStorageBufferRange, max_intermediate_mib (> 0: the --max-buffer-mb budget on the intermediates;
// its reason reads "intermediates X MiB over --max-buffer-mb Y (not allocated)"), the device's largest
// device-local heap and the host's available memory (MemAvailable: Linux overcommits, so a
// frame beyond it would meet the OOM killer rather than std::bad_alloc). Throws for invalid options (check_options).
std::string plan_frame(vk::Context* ctx, const Method& method, const FilterOptions& options, int width_px,
                       int height_px, double max_intermediate_mib, FramePlan& plan);

}  // namespace bokeh
