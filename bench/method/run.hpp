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
CocInput cpu_coc_pass(const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern,
                      int threads = default_cpu_threads());

// The CPU reference, CoC pass included.
Image run_cpu(const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, int threads);

// One GPU frame (warmed up first). `pass_times` receives per-pass milliseconds if given.
Image run_gpu(vk::Context& ctx, const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, std::vector<vk::PassTime>* pass_times = nullptr);

}  // namespace bokeh
