// GPU spiral bokeh: spiral_blur() of spiral.cpp on the GPU, with the same spiral table (computed once
// on the CPU in double: the GPU's sin and cos are not the CPU's) and the same float operations.
#include "spiral_gpu.hpp"

#include <bit>
#include <cstdint>

#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
// Adjacent pixels per invocation of the spiral pass (OUTPUTS in shaders/spiral/spiral.comp).
constexpr std::uint32_t kOutputs = 4;

class SpiralGpu final : public gpu::GpuFilter {
 public:
  SpiralGpu(gpu::GpuFrame& frame, const std::vector<SpiralSample>& spiral, float clamp_factor)
      : frame_(frame),
        table_(upload_table(frame.ctx, spiral)),
        signed_coc_(frame),
        // The clamp factor is a float specialization constant: its 4 bytes travel as an int32.
        spiral_(frame.ctx, vk::spirv("spiral/spiral"), {kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams),
                {static_cast<std::int32_t>(spiral.size()), std::bit_cast<std::int32_t>(clamp_factor)}) {
    spiral_.bind(0, table_);
    spiral_.bind(1, signed_coc_.buffer);
    spiral_.bind(2, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    signed_coc_.dispatch(cmd);
    timer.end_pass(cmd, "prepare");
    spiral_.dispatch(cmd, &frame_.params, (frame_.width() + kOutputs - 1) / kOutputs, frame_.height());
    timer.end_pass(cmd, "spiral");
  }
  std::uint64_t intermediate_bytes() const override { return table_.allocated_bytes() + signed_coc_.buffer.allocated_bytes(); }

 private:
  static vk::Buffer upload_table(vk::Context& ctx, const std::vector<SpiralSample>& spiral) {
    static_assert(sizeof(SpiralSample) == 32, "two vec4 per sample");
    const VkDeviceSize bytes = spiral.size() * sizeof(SpiralSample);
    // An empty spiral (spacing >= the largest radius) still needs a valid buffer.
    vk::Buffer b = vk::make_storage_buffer(ctx, std::max<VkDeviceSize>(32, bytes), "spiral table");
    if (!spiral.empty()) vk::upload(ctx, b, spiral.data(), bytes);
    return b;
  }
  gpu::GpuFrame& frame_;
  vk::Buffer table_;
  gpu::SignedCocPass signed_coc_;
  vk::ComputePipeline spiral_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_spiral_gpu(gpu::GpuFrame& frame, const std::vector<SpiralSample>& spiral,
                                                float clamp_factor) {
  return std::make_unique<SpiralGpu>(frame, spiral, clamp_factor);
}

}  // namespace bokeh
