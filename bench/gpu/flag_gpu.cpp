// GPU FLAG: horizontal pass into a 3D storage image (ceil(N/2) layers), vertical pass out.
// A 3D image rather than a buffer: lavapipe's storage buffers stop at 128 MiB, and the paper's
// 1080p/41x41 buffer is 332 MiB.
#include <cstdint>

#include "flag_horizontal_f16.spv.h"
#include "flag_horizontal_f32.spv.h"
#include "flag_vertical_f16.spv.h"
#include "flag_vertical_f32.spv.h"
#include "gpu_filters.hpp"

namespace bokeh::gpu {

VkFormat layer_format(LayerPrecision precision) {
  return precision == LayerPrecision::f32 ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R16G16B16A16_SFLOAT;
}

namespace {

class Flag final : public GpuFilter {
 public:
  Flag(GpuFrame& frame, const FilterOptions& options)
      : Flag(frame, options, layer_precision_from_string(options.precision)) {}
  Flag(GpuFrame& frame, const FilterOptions& options, LayerPrecision precision)
      : frame_(frame),
        layers_(frame.ctx, layer_format(precision), frame.width(), frame.height(),
                static_cast<std::uint32_t>(options.pattern.layers())),
        horizontal_(frame.ctx, precision == LayerPrecision::f32 ? std::span<const std::uint32_t>(flag_horizontal_f32_spv)
                                                                        : std::span<const std::uint32_t>(flag_horizontal_f16_spv),
                    {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}, sizeof(PassParams),
                    {options.pattern.layers()}),
        vertical_(frame.ctx, precision == LayerPrecision::f32 ? std::span<const std::uint32_t>(flag_vertical_f32_spv)
                                                                      : std::span<const std::uint32_t>(flag_vertical_f16_spv),
                  {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}, sizeof(PassParams)) {
    horizontal_.bind(0, frame.packed);
    horizontal_.bind(1, layers_);
    vertical_.bind(0, layers_);
    vertical_.bind(1, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    horizontal_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
    timer.end_pass(cmd, "horizontal");
    vertical_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
    timer.end_pass(cmd, "vertical");
  }
  std::uint64_t intermediate_bytes() const override { return layers_.allocated_bytes(); }

 private:
  GpuFrame& frame_;
  vk::StorageImage3D layers_;
  vk::ComputePipeline horizontal_, vertical_;
};

}  // namespace

std::unique_ptr<GpuFilter> make_flag_gpu(GpuFrame& frame, const FilterOptions& options) {
  return std::make_unique<Flag>(frame, options);
}

}  // namespace bokeh::gpu
