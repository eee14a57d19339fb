#pragma once
// scene (colour + depth) -> circle of confusion -> filter passes, on the CPU or the GPU.
#include <vector>

#include "filters.hpp"
#include "lens.hpp"
#include "scene.hpp"
#include "sweep.hpp"
#include "vk/context.hpp"

namespace bokeh {

struct CocInput {
  Image radius_px;  // clamped to the pattern's max radius
  Image packed;     // (rgb / discrete disc area, radius)
};
CocInput cpu_coc_pass(const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern);

Image run_cpu(const FilterRegistration& filter, const Image& color, const Image& depth_m, const Lens& lens,
              const gpu::FilterOptions& options, int threads);

// One GPU frame (warmed up first). `pass_times` receives per-pass milliseconds if given.
Image run_gpu(vk::Context& ctx, const FilterRegistration& filter, const Image& color, const Image& depth_m,
              const Lens& lens, const gpu::FilterOptions& options, std::vector<vk::PassTime>* pass_times = nullptr);

// Times one method on "gpu" (Vulkan timestamps; ctx required) or "cpu" (wall clock, CoC pass
// included) through `sweep`, under the Google Benchmark name `name`. `output`, if given, receives
// the image the timed frames produced, so its error can be reported next to its time.
PointStats measure_method(Sweep& sweep, const std::string& name, vk::Context* ctx, const FilterRegistration& filter,
                          const std::string& backend, const Scene& scene, const Lens& lens,
                          const gpu::FilterOptions& options, int cpu_threads, Image* output = nullptr);

}  // namespace bokeh
