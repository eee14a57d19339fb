#include "calibration.hpp"

#include <chrono>
#include <cstring>
#include <thread>

#include "gpu_frame.hpp"
#include "parallel.hpp"
#include "vk/compute_pipeline.hpp"
#include "vk/memory.hpp"
#include "vk/spirv.hpp"
#include "vk/timestamps.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
constexpr int kFmaIterations = 1024, kFmaFlopsPerIteration = 64;  // 8 vec4 multiply-adds
constexpr std::uint32_t kRowWidth = 1024;                          // invocations per row of the dispatch

// One compute pass, `frames` dispatches between one pair of timestamps.
class GpuKernel final : public runner::Target {
 public:
  GpuKernel(vk::Context& ctx, const std::string& variant, std::vector<vk::Buffer> buffers, std::uint32_t width,
            std::uint32_t height, std::vector<std::int32_t> spec)
      : ctx_(ctx),
        buffers_(std::move(buffers)),
        pass_(ctx, vk::spirv(variant), std::vector<VkDescriptorType>(buffers_.size(), kBuffer),
              sizeof(gpu::PassParams), std::move(spec)),
        timer_(ctx) {
    params_ = {static_cast<std::int32_t>(width), static_cast<std::int32_t>(height), 0, 1, 0, 0, 0};
    for (std::uint32_t b = 0; b < buffers_.size(); ++b) pass_.bind(b, buffers_[b]);
  }
  void warm_up() override { measure(1); }
  runner::Sample measure(int frames) override {
    ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
      timer_.begin_frame(cmd);
      for (int f = 0; f < frames; ++f) pass_.dispatch(cmd, &params_, params_.width_px, params_.height_px);
      timer_.end_pass(cmd, "kernel");
    });
    return {vk::frame_ms(timer_.read()) / frames, {}};
  }

 private:
  vk::Context& ctx_;
  std::vector<vk::Buffer> buffers_;
  vk::ComputePipeline pass_;
  vk::TimestampQueries timer_;
  gpu::PassParams params_{};
};

class CpuKernel final : public runner::Target {
 public:
  explicit CpuKernel(std::function<void()> frame) : frame_(std::move(frame)) {}
  void warm_up() override { frame_(); }
  runner::Sample measure(int frames) override {
    const auto start = std::chrono::steady_clock::now();
    for (int f = 0; f < frames; ++f) frame_();
    return {std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / frames, {}};
  }

 private:
  std::function<void()> frame_;
};

// Multiply-adds over independent accumulators, as many as the compiler can keep in vector registers.
float fma_loop(long iterations, float seed) {
  constexpr int kLanes = 64;
  float acc[kLanes];
  for (int j = 0; j < kLanes; ++j) acc[j] = seed + static_cast<float>(j);
  for (long n = 0; n < iterations; ++n)
    for (int j = 0; j < kLanes; ++j) acc[j] = acc[j] * 0.999999f + 1e-7f;
  float sum = 0;
  for (float a : acc) sum += a;
  return sum;
}

}  // namespace

std::vector<CalibrationKernel> gpu_calibration(vk::Context& ctx, std::uint64_t copy_bytes) {
  std::vector<CalibrationKernel> out;
  const std::uint32_t copy_rows = static_cast<std::uint32_t>(copy_bytes / 16 / kRowWidth);
  const std::uint64_t copied = static_cast<std::uint64_t>(copy_rows) * kRowWidth * 16;
  std::vector<vk::Buffer> copy_buffers;
  copy_buffers.push_back(vk::make_storage_buffer(ctx, copied, "calibration copy source"));
  copy_buffers.push_back(vk::make_storage_buffer(ctx, copied, "calibration copy destination"));
  out.push_back({"gpu_copy", 2.0 * copied, 0,
                 std::make_unique<GpuKernel>(ctx, "common/calibration_copy", std::move(copy_buffers), kRowWidth,
                                             copy_rows, std::vector<std::int32_t>{})});
  const std::uint32_t fma_rows = 64;
  std::vector<vk::Buffer> fma_buffers;
  fma_buffers.push_back(vk::make_storage_buffer(ctx, std::uint64_t{kRowWidth} * fma_rows * 16, "calibration FMA output"));
  out.push_back({"gpu_fma", 0, 1.0 * kRowWidth * fma_rows * kFmaIterations * kFmaFlopsPerIteration,
                 std::make_unique<GpuKernel>(ctx, "common/calibration_fma", std::move(fma_buffers), kRowWidth, fma_rows,
                                             std::vector<std::int32_t>{kFmaIterations})});
  return out;
}

std::vector<CalibrationKernel> cpu_calibration(int threads, std::uint64_t copy_bytes) {
  threads = threads > 0 ? threads : default_cpu_threads();
  std::vector<CalibrationKernel> out;
  auto src = std::make_shared<std::vector<char>>(copy_bytes, 1), dst = std::make_shared<std::vector<char>>(copy_bytes, 0);
  const std::size_t chunk = (copy_bytes + threads - 1) / threads;
  out.push_back({"cpu_copy", 2.0 * copy_bytes, 0, std::make_unique<CpuKernel>([=] {
                   parallel_rows(threads, threads, [&](int t) {
                     const std::size_t begin = std::min<std::size_t>(copy_bytes, t * chunk);
                     const std::size_t end = std::min<std::size_t>(copy_bytes, begin + chunk);
                     std::memcpy(dst->data() + begin, src->data() + begin, end - begin);
                   });
                 })});
  constexpr long kIterations = 1 << 20;
  auto sink = std::make_shared<std::vector<float>>(threads);
  out.push_back({"cpu_fma", 0, 2.0 * 64 * kIterations * threads, std::make_unique<CpuKernel>([=] {
                   parallel_rows(threads, threads, [&](int t) { (*sink)[t] = fma_loop(kIterations, (*sink)[t]); });
                 })});
  return out;
}

}  // namespace bokeh
