// GPU hexagonal bokeh: hexagon_passes() of hexagon.cpp on the GPU, pass for pass, with the same float
// operations in the same order (shaders/hexagon/).
#include "hexagon_gpu.hpp"

#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
// Adjacent pixels per invocation of both blur passes (OUTPUTS in shaders/hexagon/hexagon.glsl).
constexpr std::uint32_t kOutputs = 4;

class HexagonGpu final : public gpu::GpuFilter {
 public:
  HexagonGpu(gpu::GpuFrame& frame, int taps)
      : frame_(frame),
        signed_coc_(image_buffer("hexagon signed-CoC buffer")),
        up_(image_buffer("hexagon pass-1 output 1 (up)")),
        mean_(image_buffer("hexagon pass-1 output 2 (up + down-left) / 2")),
        prepare_(frame.ctx, vk::spirv("common/signed_coc"), {kBuffer, kBuffer, kBuffer, kBuffer},
                 sizeof(gpu::PassParams)),
        first_(frame.ctx, vk::spirv("hexagon/first"), {kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams), {taps}),
        second_(frame.ctx, vk::spirv("hexagon/second"), {kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams),
                {taps}) {
    prepare_.bind(0, frame.color);
    prepare_.bind(1, frame.depth);
    prepare_.bind(2, frame.packed);
    prepare_.bind(3, signed_coc_);
    first_.bind(0, signed_coc_);
    first_.bind(1, up_);
    first_.bind(2, mean_);
    second_.bind(0, up_);
    second_.bind(1, mean_);
    second_.bind(2, signed_coc_);
    second_.bind(3, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    const std::uint32_t w = frame_.width(), h = frame_.height();
    prepare_.dispatch(cmd, &frame_.params, w, h);
    timer.end_pass(cmd, "prepare");
    first_.dispatch(cmd, &frame_.params, (w + kOutputs - 1) / kOutputs, h);
    timer.end_pass(cmd, "up_and_downleft");
    second_.dispatch(cmd, &frame_.params, (w + kOutputs - 1) / kOutputs, h);
    timer.end_pass(cmd, "rhombi");
  }
  std::uint64_t intermediate_bytes() const override {
    return signed_coc_.allocated_bytes() + up_.allocated_bytes() + mean_.allocated_bytes();
  }

 private:
  vk::Buffer image_buffer(const char* what) {
    return vk::make_storage_buffer(frame_.ctx, static_cast<VkDeviceSize>(frame_.width()) * frame_.height() * 16, what);
  }
  gpu::GpuFrame& frame_;
  vk::Buffer signed_coc_, up_, mean_;
  vk::ComputePipeline prepare_, first_, second_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_hexagon_gpu(gpu::GpuFrame& frame, int taps) {
  return std::make_unique<HexagonGpu>(frame, taps);
}

}  // namespace bokeh
