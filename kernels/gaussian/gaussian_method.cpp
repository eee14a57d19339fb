// gaussian: a separable Gaussian blur with the scene's largest CoC as its 2-sigma radius, mixed with
// the sharp image by CoC: the speed floor engines used before bokeh (see gaussian.hpp).
#include <algorithm>

#include "gaussian.hpp"
#include "method.hpp"
#include "vk/memory.hpp"
#include "vk/spirv.hpp"

namespace bokeh::methods {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
constexpr VkDescriptorType kUniform = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
constexpr VkDescriptorType kTexels = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;

// How the passes load, per device (spec constants OUTPUTS and TEXEL_LOADS in shaders/gaussian/taps.glsl;
// every output sums its taps in the same order either way). lavapipe runs 8 lanes as SIMD and turns a
// storage-buffer load in the tap loop into a loop of per-lane scalar loads: there 4 outputs per
// invocation (each loaded input serves 4 taps, through a window shifted in registers) and texel
// fetches (one vector gather) cut the loads, as for the circular filters (kernels/circular). A GPU
// serves plain 16-byte loads at the L1 rate and gains nothing from a window that costs registers, so
// it keeps one output per invocation and the storage-buffer loads (not measured: no GPU was lent).
struct PassShape {
  int outputs;
  bool texel_loads;
};
PassShape pass_shape_for(const vk::DeviceInfo& device) {
  return device.is_software() ? PassShape{4, true} : PassShape{1, false};
}

// The taps, four to a vec4 (std140 array of vec4 in shaders/gaussian/taps.glsl).
std::uint64_t taps_block_bytes(int radius_px) { return 16 * ((2 * static_cast<std::uint64_t>(radius_px) + 1 + 3) / 4); }

class GaussianGpu final : public gpu::GpuFilter {
 public:
  GaussianGpu(gpu::GpuFrame& frame, int radius_px, PassShape shape)
      : frame_(frame),
        shape_(shape),
        taps_(upload_taps(frame.ctx, radius_px)),
        blurred_(vk::make_storage_buffer(frame.ctx, pixels() * 16, "gaussian intermediate",
                                         VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT)),
        color_texels_(frame.ctx, frame.color, VK_FORMAT_R32G32B32A32_SFLOAT, 16, "colour buffer"),
        blurred_texels_(frame.ctx, blurred_, VK_FORMAT_R32G32B32A32_SFLOAT, 16, "gaussian intermediate"),
        horizontal_(frame.ctx, vk::spirv("gaussian/horizontal"), {kUniform, kBuffer, kTexels, kBuffer},
                    sizeof(gpu::PassParams), {radius_px, shape.outputs, shape.texel_loads ? 1 : 0}),
        vertical_(frame.ctx, vk::spirv("gaussian/vertical"), {kUniform, kBuffer, kTexels, kBuffer, kBuffer, kBuffer},
                  sizeof(gpu::PassParams), {radius_px, shape.outputs, shape.texel_loads ? 1 : 0}) {
    horizontal_.bind(0, taps_);
    horizontal_.bind(1, frame.color);
    horizontal_.bind(2, color_texels_);
    horizontal_.bind(3, blurred_);
    vertical_.bind(0, taps_);
    vertical_.bind(1, blurred_);
    vertical_.bind(2, blurred_texels_);
    vertical_.bind(3, frame.color);
    vertical_.bind(4, frame.packed);
    vertical_.bind(5, frame.output);
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    const auto outputs = static_cast<std::uint32_t>(shape_.outputs);
    horizontal_.dispatch(cmd, &frame_.params, (frame_.width() + outputs - 1) / outputs, frame_.height());
    timer.end_pass(cmd, "horizontal");
    vertical_.dispatch(cmd, &frame_.params, frame_.width(), (frame_.height() + outputs - 1) / outputs);
    timer.end_pass(cmd, "vertical");
  }
  std::uint64_t intermediate_bytes() const override { return taps_.allocated_bytes() + blurred_.allocated_bytes(); }

 private:
  VkDeviceSize pixels() const { return static_cast<VkDeviceSize>(frame_.width()) * frame_.height(); }
  static vk::Buffer upload_taps(vk::Context& ctx, int radius_px) {
    std::vector<float> block(taps_block_bytes(radius_px) / sizeof(float), 0.0f);
    const std::vector<float> taps = gaussian_taps(radius_px);
    std::copy(taps.begin(), taps.end(), block.begin());
    vk::Buffer b = vk::make_uniform_buffer(ctx, block.size() * sizeof(float), "gaussian taps");
    vk::upload(ctx, b, block.data(), block.size() * sizeof(float));
    return b;
  }
  gpu::GpuFrame& frame_;
  PassShape shape_;
  vk::Buffer taps_, blurred_;
  vk::TexelView color_texels_, blurred_texels_;
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
    if (radius_of(o) < 1) return "gaussian needs a largest CoC k (N - 1) / 2 >= 1 px";
    // The taps fill a uniform buffer, which every device offers up to 16 KiB (lavapipe: 64 KiB).
    if (taps_block_bytes(radius_of(o)) > 16384) return "gaussian's taps fit a 16 KiB uniform buffer: largest CoC <= 2047 px";
    return "";
  };
  m.cpu_reference = [](const CpuInput& in) {
    return gaussian_blur(in.color, in.radius_px, radius_of(in.options), in.threads);
  };
  m.make_gpu = [](gpu::GpuFrame& frame, const FilterOptions& o) -> std::unique_ptr<gpu::GpuFilter> {
    return std::make_unique<GaussianGpu>(frame, radius_of(o), pass_shape_for(frame.ctx.info()));
  };
  m.work = [](const FilterOptions& o, int w, int h) {
    const double px = static_cast<double>(w) * h, taps = px * (2.0 * radius_of(o) + 1);
    return std::vector<PassWork>{{"horizontal", taps, px * 16, px * 16}, {"vertical", taps, px * 48, px * 16}};
  };
  m.gpu_memory = [](const FilterOptions& o, int w, int h, vk::Context*) {
    MemoryUse use;
    use.bytes = static_cast<std::uint64_t>(w) * h * 16 + taps_block_bytes(radius_of(o));
    return use;
  };
  m.cpu_memory_bytes = [](const FilterOptions&, int w, int h) { return static_cast<std::uint64_t>(w) * h * 3 * 4; };
  m.gpu_tolerance = [](const FilterOptions&) { return 1e-5; };  // same taps and order; f32 rounding only
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  m.energy_note = "normalised taps: a constant-radius image is one convolution";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
