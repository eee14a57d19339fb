// gaussian: a separable Gaussian blur with the scene's largest CoC as its 2-sigma radius, mixed with
// the sharp image by CoC: the speed floor engines used before bokeh (see gaussian.hpp).
#include "gaussian.hpp"
#include "method.hpp"
#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh::methods {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;

class GaussianGpu final : public gpu::GpuFilter {
 public:
  GaussianGpu(gpu::GpuFrame& frame, int radius_px)
      : frame_(frame),
        weights_(upload_weights(frame.ctx, gaussian_taps(radius_px))),
        blurred_(vk::make_storage_buffer(frame.ctx, static_cast<VkDeviceSize>(frame.width()) * frame.height() * 16,
                                         "gaussian intermediate")),
        horizontal_(frame.ctx, vk::spirv("gaussian/horizontal"), {kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams),
                    {radius_px}),
        vertical_(frame.ctx, vk::spirv("gaussian/vertical"), {kBuffer, kBuffer, kBuffer, kBuffer, kBuffer},
                  sizeof(gpu::PassParams), {radius_px}) {
    horizontal_.bind(0, weights_);
    horizontal_.bind(1, frame.color);
    horizontal_.bind(2, blurred_);
    vertical_.bind(0, weights_);
    vertical_.bind(1, blurred_);
    vertical_.bind(2, frame.color);
    vertical_.bind(3, frame.packed);
    vertical_.bind(4, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    horizontal_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
    timer.end_pass(cmd, "horizontal");
    vertical_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
    timer.end_pass(cmd, "vertical");
  }
  std::uint64_t intermediate_bytes() const override { return weights_.allocated_bytes() + blurred_.allocated_bytes(); }

 private:
  static vk::Buffer upload_weights(vk::Context& ctx, const std::vector<float>& taps) {
    vk::Buffer b = vk::make_storage_buffer(ctx, taps.size() * sizeof(float), "gaussian weights");
    vk::upload(ctx, b, taps.data(), taps.size() * sizeof(float));
    return b;
  }
  gpu::GpuFrame& frame_;
  vk::Buffer weights_, blurred_;
  vk::ComputePipeline horizontal_, vertical_;
};

int radius_of(const FilterOptions& o) { return static_cast<int>(o.pattern.max_radius_px()); }

}  // namespace

void declare_gaussian(std::vector<Method>& methods) {
  Method m;
  m.name = "gaussian";
  m.description = "separable Gaussian blur, 2 sigma = the largest CoC, mixed with the sharp image by CoC (pre-bokeh "
                  "engines' speed floor)";
  m.precisions = {"f32"};
  m.samples_pattern = false;
  m.unsupported = [](const FilterOptions& o, int, int) -> std::string {
    return radius_of(o) < 1 ? "gaussian needs a largest CoC k (N - 1) / 2 >= 1 px" : "";
  };
  m.cpu_reference = [](const CpuInput& in) {
    return gaussian_blur(in.color, in.radius_px, radius_of(in.options), in.threads);
  };
  m.make_gpu = [](gpu::GpuFrame& frame, const FilterOptions& o) -> std::unique_ptr<gpu::GpuFilter> {
    return std::make_unique<GaussianGpu>(frame, radius_of(o));
  };
  m.work = [](const FilterOptions& o, int w, int h) {
    const double px = static_cast<double>(w) * h, taps = px * (2.0 * radius_of(o) + 1);
    return std::vector<PassWork>{{"horizontal", taps, px * 16, px * 16}, {"vertical", taps, px * 48, px * 16}};
  };
  m.gpu_memory = [](const FilterOptions& o, int w, int h, vk::Context*) {
    MemoryUse use;
    use.bytes = static_cast<std::uint64_t>(w) * h * 16 + (2 * radius_of(o) + 1) * sizeof(float);
    return use;
  };
  m.cpu_memory_bytes = [](const FilterOptions&, int w, int h) { return static_cast<std::uint64_t>(w) * h * 3 * 4; };
  m.gpu_tolerance = [](const FilterOptions&) { return 1e-5; };  // same taps and order; f32 rounding only
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  m.energy_note = "normalised taps: a constant-radius image is one convolution";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
