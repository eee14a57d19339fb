// GPU naive quadratic gather: one pass over the packed input.
#include <cstdint>

#include "gpu_filters.hpp"
#include "naive_gather.spv.h"

namespace bokeh::gpu {

namespace {

class NaiveGather final : public GpuFilter {
 public:
  explicit NaiveGather(GpuFrame& frame)
      : frame_(frame),
        gather_(frame.ctx, naive_gather_spv, {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                sizeof(PassParams)) {
    gather_.bind(0, frame.packed);
    gather_.bind(1, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    gather_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
    timer.end_pass(cmd, "gather");
  }
  std::uint64_t intermediate_bytes() const override { return 0; }

 private:
  GpuFrame& frame_;
  vk::ComputePipeline gather_;
};

}  // namespace

std::unique_ptr<GpuFilter> make_naive_gpu(GpuFrame& frame, const FilterOptions&) {
  return std::make_unique<NaiveGather>(frame);
}

}  // namespace bokeh::gpu
