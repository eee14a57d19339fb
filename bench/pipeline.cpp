#include "pipeline.hpp"

#include "coc.hpp"

namespace bokeh {

CocInput cpu_coc_pass(const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern) {
  CocInput in;
  in.radius_px = coc_radius_image(depth_m, lens, pattern.max_radius_px());
  in.packed = pack_gather_input(color, in.radius_px, pattern);
  return in;
}

Image run_cpu(const FilterRegistration& filter, const Image& color, const Image& depth_m, const Lens& lens,
              const gpu::FilterOptions& options, int threads) {
  validate(options.pattern);
  check_options(filter, options);
  const CocInput coc = cpu_coc_pass(color, depth_m, lens, options.pattern);
  return filter.cpu_reference({color, depth_m, lens, coc.radius_px, coc.packed, options, threads});
}

Image run_gpu(vk::Context& ctx, const FilterRegistration& filter, const Image& color, const Image& depth_m,
              const Lens& lens, const gpu::FilterOptions& options, std::vector<vk::PassTime>* pass_times) {
  validate(options.pattern);
  check_options(filter, options);
  coc_radius_image(depth_m, lens, options.pattern.max_radius_px());  // validates depth and lens with clear errors
  gpu::GpuFrame frame(ctx, color, depth_m, lens, options.pattern);
  auto gpu_filter = filter.make_gpu(frame, options);
  vk::TimestampQueries timer(ctx, 16);
  gpu::warm_up(frame, *gpu_filter, timer);
  auto times = gpu::run_frame(frame, *gpu_filter, timer);
  if (pass_times) *pass_times = std::move(times);
  return frame.read_output();
}

PointStats measure_method(Sweep& sweep, const std::string& name, vk::Context* ctx, const FilterRegistration& filter,
                          const std::string& backend, const Scene& scene, const Lens& lens,
                          const gpu::FilterOptions& options, int cpu_threads, Image* output) {
  check_options(filter, options);
  if (backend == "gpu") {
    if (!ctx) throw std::invalid_argument("gpu backend without a Vulkan context");
    gpu::GpuFrame frame(*ctx, scene.color, scene.depth_m, lens, options.pattern);
    auto gpu_filter = filter.make_gpu(frame, options);
    vk::TimestampQueries timer(*ctx, 16);
    const PointStats stats = sweep.measure(name, [&] { gpu::warm_up(frame, *gpu_filter, timer); },
                                           [&] { return gpu::run_frame(frame, *gpu_filter, timer); }, true);
    if (output) *output = frame.read_output();
    return stats;
  }
  if (backend == "cpu") {
    Image last;
    const PointStats stats = sweep.measure(name, [] {},
                                           [&] {
                                             last = run_cpu(filter, scene.color, scene.depth_m, lens, options,
                                                            cpu_threads);
                                             return std::vector<vk::PassTime>{};
                                           },
                                           false);
    if (output) *output = std::move(last);
    return stats;
  }
  throw std::invalid_argument("backend must be gpu or cpu, got '" + backend + "'");
}

}  // namespace bokeh
