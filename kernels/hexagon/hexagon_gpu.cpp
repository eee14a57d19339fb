// GPU hexagonal bokeh: hexagon_passes() of hexagon.cpp on the GPU, pass for pass, with the same float
// operations in the same order (shaders/hexagon/).
#include "hexagon_gpu.hpp"

#include <bit>
#include <vector>

#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
// Adjacent pixels per invocation of both blur passes (OUTPUTS in shaders/hexagon/hexagon.glsl).
constexpr std::uint32_t kOutputs = 4;

class HexagonGpu final : public gpu::GpuFilter {
 public:
  HexagonGpu(gpu::GpuFrame& frame, int taps, const HexagonDirections& d)
      : frame_(frame),
        signed_coc_(frame),
        up_(image_buffer("hexagon pass-1 output 1 (up)")),
        mean_(image_buffer("hexagon pass-1 output 2 (up + down-left) / 2")),
        first_(frame.ctx, vk::spirv("hexagon/first"), {kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams),
               constants(taps, d)),
        second_(frame.ctx, vk::spirv("hexagon/second"), {kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams),
                constants(taps, d)) {
    first_.bind(0, signed_coc_.buffer);
    first_.bind(1, up_);
    first_.bind(2, mean_);
    second_.bind(0, up_);
    second_.bind(1, mean_);
    second_.bind(2, signed_coc_.buffer);
    second_.bind(3, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    const std::uint32_t w = frame_.width(), h = frame_.height();
    signed_coc_.dispatch(cmd);
    timer.end_pass(cmd, "prepare");
    first_.dispatch(cmd, &frame_.params, (w + kOutputs - 1) / kOutputs, h);
    timer.end_pass(cmd, "up_and_downleft");
    second_.dispatch(cmd, &frame_.params, (w + kOutputs - 1) / kOutputs, h);
    timer.end_pass(cmd, "rhombi");
  }
  std::uint64_t intermediate_bytes() const override {
    return signed_coc_.buffer.allocated_bytes() + up_.allocated_bytes() + mean_.allocated_bytes();
  }

 private:
  // TAPS, then the directions (their float bits) and whether up is on the grid: hexagon.glsl's ids 1..7.
  static std::vector<std::int32_t> constants(int taps, const HexagonDirections& d) {
    return {taps,
            std::bit_cast<std::int32_t>(d.up[0]),
            std::bit_cast<std::int32_t>(d.up[1]),
            std::bit_cast<std::int32_t>(d.downleft[0]),
            std::bit_cast<std::int32_t>(d.downleft[1]),
            std::bit_cast<std::int32_t>(d.downright[0]),
            std::bit_cast<std::int32_t>(d.downright[1]),
            d.up_on_axis ? 1 : 0};
  }
  vk::Buffer image_buffer(const char* what) {
    return vk::make_storage_buffer(frame_.ctx, static_cast<VkDeviceSize>(frame_.width()) * frame_.height() * 16, what);
  }
  gpu::GpuFrame& frame_;
  gpu::SignedCocPass signed_coc_;
  vk::Buffer up_, mean_;
  vk::ComputePipeline first_, second_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_hexagon_gpu(gpu::GpuFrame& frame, int taps, const HexagonDirections& directions) {
  return std::make_unique<HexagonGpu>(frame, taps, directions);
}

}  // namespace bokeh
