#pragma once
// The machine's own limits, measured in the same run as the filters and timed every round (the
// runner's probes): a bandwidth-bound copy and a compute-bound multiply-add loop, on the Vulkan
// device and on the CPU. Their work is exact by construction, so achieved GB/s and GFLOP/s follow
// from their times, and a filter's throughput can be read as a fraction of them.
#include <memory>
#include <string>
#include <vector>

#include "runner.hpp"
#include "vk/context.hpp"

namespace bokeh {

struct CalibrationKernel {
  std::string name;  // gpu_copy, gpu_fma, cpu_copy, cpu_fma
  double bytes = 0;  // moved per frame (read + written)
  double flops = 0;  // floating-point operations per frame (a multiply-add is two)
  std::unique_ptr<runner::Target> target;
};

// copy_bytes: the size of the copied buffer (read once, written once per frame).
std::vector<CalibrationKernel> gpu_calibration(vk::Context& ctx, std::uint64_t copy_bytes = 64ull << 20);
std::vector<CalibrationKernel> cpu_calibration(int threads, std::uint64_t copy_bytes = 64ull << 20);

}  // namespace bokeh
