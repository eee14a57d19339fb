#include "run.hpp"

#include "coc.hpp"

namespace bokeh {

CocInput cpu_coc_pass(const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern,
                      int threads) {
  CocInput in;
  in.radius_px = coc_radius_image(depth_m, lens, pattern.max_radius_px());
  in.packed = pack_gather_input(color, in.radius_px, pattern, threads);
  return in;
}

Image run_cpu(const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, int threads) {
  check_options(method, options);
  const CocInput coc = cpu_coc_pass(color, depth_m, lens, options.pattern, threads);
  return method.cpu_reference({color, depth_m, lens, coc.radius_px, coc.packed, options, threads});
}

Image run_gpu(vk::Context& ctx, const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, std::vector<vk::PassTime>* pass_times) {
  check_options(method, options);
  if (const std::string missing = ctx.unmet(method.needs(options)); !missing.empty())
    throw std::runtime_error(method.name + " needs " + missing + ", which " + ctx.info().name + " lacks");
  coc_radius_image(depth_m, lens, options.pattern.max_radius_px());  // validates depth and lens with clear errors
  gpu::GpuFrame frame(ctx, color, depth_m, lens, options.pattern);
  auto gpu_filter = method.make_gpu(frame, options);
  vk::TimestampQueries timer(ctx);
  gpu::warm_up(frame, *gpu_filter, timer);
  auto times = gpu::run_frames(frame, *gpu_filter, timer);
  if (pass_times) *pass_times = std::move(times);
  return frame.read_output();
}

}  // namespace bokeh
