// GPU naive quadratic gather: one pass over the packed input.
#include "naive_gpu.hpp"

#include "vk/spirv.hpp"

namespace bokeh {

namespace {

class NaiveGather final : public gpu::GpuFilter {
 public:
  explicit NaiveGather(gpu::GpuFrame& frame)
      : frame_(frame),
        gather_(frame.ctx, vk::spirv("naive/gather"),
                {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}, sizeof(gpu::PassParams)) {
    gather_.bind(0, frame.packed);
    gather_.bind(1, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    gather_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
    timer.end_pass(cmd, "gather");
  }
  std::uint64_t intermediate_bytes() const override { return 0; }

 private:
  gpu::GpuFrame& frame_;
  vk::ComputePipeline gather_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_naive_gpu(gpu::GpuFrame& frame, const FilterOptions&) {
  return std::make_unique<NaiveGather>(frame);
}

}  // namespace bokeh
