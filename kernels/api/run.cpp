#include "run.hpp"

#include <fstream>
#include <new>
#include <stdexcept>

#include <unistd.h>

#include <fmt/format.h>

#include "coc.hpp"

namespace bokeh {

namespace {

// The lens is what the user gave; the options carry its aperture to the method. They must agree.
void check_aperture(const Lens& lens, const FilterOptions& options) {
  if (!(lens.aperture == options.aperture))
    throw std::invalid_argument(fmt::format("the lens's aperture is {} but the method was asked for {}",
                                            lens.aperture.name(), options.aperture.name()));
}

std::string mib(double bytes) { return fmt::format("{:.1f} MiB", bytes / (1024.0 * 1024.0)); }

std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : 0;
}

// MemAvailable (what can be had without swapping): Linux overcommits, so a frame larger than this
// is not refused by the allocator but ends with the OOM killer. Falls back to the physical size.
std::uint64_t available_memory_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::uint64_t kib = 0;
  std::string unit;
  while (meminfo >> key >> kib >> unit)
    if (key == "MemAvailable:") return kib * 1024;
  return physical_memory_bytes();
}

}  // namespace

CocInput cpu_coc_pass(const Image& color, const Image& depth_m, const Lens& lens, const GatherPattern& pattern,
                      int threads) {
  check_color(color);
  CocInput in;
  in.radius_px = coc_radius_image(depth_m, lens, pattern.max_radius_px());
  in.packed = pack_gather_input(color, in.radius_px, pattern, threads);
  return in;
}

Image run_cpu(const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, int threads, nlohmann::json* stats) {
  check_options(method, options);
  check_aperture(lens, options);
  const CocInput coc = cpu_coc_pass(color, depth_m, lens, options.pattern, threads);
  if (stats) *stats = nlohmann::json::object();
  try {
    return method.cpu_reference({color, depth_m, lens, coc.radius_px, coc.packed, options, threads, stats});
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(fmt::format(
        "out of host memory in the {} CPU reference at {}x{} (its model: {} of intermediates)", method.name,
        color.width, color.height, mib(static_cast<double>(method.cpu_memory_bytes(options, color.width, color.height)))));
  }
}

Image run_gpu(vk::Context& ctx, const Method& method, const Image& color, const Image& depth_m, const Lens& lens,
              const FilterOptions& options, std::vector<vk::PassTime>* pass_times, nlohmann::json* stats) {
  check_options(method, options);
  check_aperture(lens, options);
  if (const std::string missing = ctx.unmet(method.needs(options)); !missing.empty())
    throw std::runtime_error(method.name + " needs " + missing + ", which " + ctx.info().name + " lacks");
  check_color(color);
  coc_radius_image(depth_m, lens, options.pattern.max_radius_px());  // validates depth and lens with clear errors
  gpu::GpuFrame frame(ctx, color, depth_m, lens, options.pattern);
  auto gpu_filter = method.make_gpu(frame, options);
  vk::TimestampQueries timer(ctx);
  gpu::warm_up(frame, *gpu_filter, timer);
  auto times = gpu::run_frames(frame, *gpu_filter, timer);
  if (pass_times) *pass_times = std::move(times);
  if (stats) *stats = gpu_filter->stats();
  return frame.read_output();
}

std::string plan_frame(vk::Context* ctx, const Method& m, const FilterOptions& o, int w, int h,
                       double max_intermediate_mib, FramePlan& plan) {
  if (std::string why = aperture_unsupported(m, o); !why.empty()) return why;
  check_options(m, o);
  const auto pixels = static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h);
  // Host images every run holds: colour (12 B/px), depth (4), CoC radius (4), packed input (16), output (12).
  plan.host_bytes = pixels * 48;
  if (std::string why = m.unsupported ? m.unsupported(o, w, h) : ""; !why.empty()) return why;
  if (!ctx && !m.cpu_reference)
    return fmt::format("{} has no CPU reference (a GPU-only method package): it runs on the GPU only", m.name);
  if (ctx) {
    if (std::string missing = ctx->unmet(m.needs(o)); !missing.empty())
      return fmt::format("{} needs {}, which {} lacks", m.name, missing, ctx->info().name);
    // The frame's largest storage buffers (colour, packed input, output) hold 16 B a pixel.
    const std::uint64_t frame_buffer = pixels * 16, range = ctx->info().max_storage_buffer_range_bytes;
    if (frame_buffer > range)
      return fmt::format("the frame's colour buffer needs {}, over the device's maxStorageBufferRange of {} ({}x{} is "
                         "too large for {})",
                         mib(static_cast<double>(frame_buffer)), mib(static_cast<double>(range)), w, h, ctx->info().name);
    try {  // asking the driver may already hit a device limit (FLAG: maxImageDimension3D)
      plan.intermediates = m.gpu_memory(o, w, h, ctx);
    } catch (const std::exception& e) {
      return e.what();
    }
    plan.device_bytes = pixels * 52 + plan.intermediates.bytes;  // colour 16, depth 4, packed 16, output 16
    plan.host_bytes += pixels * 32;  // the RGBA upload copy and the staging buffer
  } else {
    plan.intermediates = MemoryUse{m.cpu_memory_bytes(o, w, h), false, nlohmann::json::object()};
    plan.host_bytes += plan.intermediates.bytes;
  }
  plan.sized = true;
  const auto intermediate = static_cast<double>(plan.intermediates.bytes);
  if (max_intermediate_mib > 0 && intermediate > max_intermediate_mib * 1024 * 1024)
    return fmt::format("intermediates {} over --max-buffer-mb {} (not allocated)", mib(intermediate), max_intermediate_mib);
  if (ctx && ctx->info().device_local_heap_bytes > 0 && plan.device_bytes > ctx->info().device_local_heap_bytes)
    return fmt::format("needs {} of device memory, more than {}'s largest device-local heap ({})",
                       mib(static_cast<double>(plan.device_bytes)), ctx->info().name,
                       mib(static_cast<double>(ctx->info().device_local_heap_bytes)));
  // 80%: headroom for what the estimate leaves out (the scene's generation, the output file).
  if (const std::uint64_t available = available_memory_bytes(); available > 0 && plan.host_bytes > available / 10 * 8)
    return fmt::format("needs {} of host memory, more than 80% of this machine's {} available ({} in all)",
                       mib(static_cast<double>(plan.host_bytes)), mib(static_cast<double>(available)),
                       mib(static_cast<double>(physical_memory_bytes())));
  return "";
}

}  // namespace bokeh
