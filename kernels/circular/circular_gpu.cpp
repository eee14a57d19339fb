// GPU circular separable convolution depth of field (Garcia, GDC 2018): circular_blur() of
// kernels/circular_separable.cpp on the GPU, pass for pass and in the same arithmetic order.
//   layers           colour + packed radius + depth -> near and far RGBA layers (rgb w, w), with
//                    w = clamp(radius / max radius, 0, 1); bracketed10: also the per-channel maxima M
//                    of each layer (a GPU reduction: subgroupMax + atomicMax, zeroed by a fill first).
//   far_horizontal   per far component c, the complex response H_c of each RGBA channel, stored f32,
//                    f16 or bracketed 10-bit (+ the f16 box sum), one storage buffer per component.
//   far_vertical     V_c = vertical complex convolution of H_c, b = sum_c A_c Re V_c + B_c Im V_c,
//                    composited over the sharp colour with the pixel's own far alpha -> output.
//   near_horizontal  as far, with the near layer and the near component count (same buffers, reused).
//   near_vertical    as far; composited over the far result with alpha = clamp(b.a, 0, 1) -> output.
// Both kernels are make_circular_kernel_for_disc(components, max radius): the disc radius is the
// pattern's max radius k (N - 1) / 2. Taps, weights and the bracketing constants O, S are computed on
// the CPU exactly as the reference does and uploaded once; kernel radius and component count are
// specialization constants. Each invocation of a horizontal (vertical) pass computes 4 adjacent
// pixels of a row (column), so every value it loads serves up to 4 taps; each output still sums its
// taps in the CPU's order. The subgroup reduction needs VK_SUBGROUP_FEATURE_ARITHMETIC_BIT in compute
// (lavapipe and desktop drivers have it).
#include <algorithm>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "circular_separable.hpp"
#include "circular_gpu.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

using gpu::GpuFrame;
using gpu::PassParams;

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
constexpr int kFarLayer = 0, kNearLayer = 1;
// Bindings of convolution.glsl: kernel, channel maxima, layer, box sum, 6 component buffers;
// the vertical pass adds colour and output.
constexpr std::uint32_t kConvolutionBindings = 10, kVerticalBindings = 12;

// The Kernel block of convolution.glsl: weight[6], bracket[6], then taps[c * (2R + 1) + i].
std::vector<float> kernel_block(const CircularKernel& k) {
  std::vector<float> block(4 * (12 + k.components * k.tap_count()), 0.0f);
  for (int c = 0; c < k.components; ++c) {
    std::vector<float> re, im;
    for (std::complex<float> t : k.taps[c]) re.push_back(t.real()), im.push_back(t.imag());
    const BracketedKernel br = bracket_kernel(re), bi = bracket_kernel(im);
    block[4 * c + 0] = k.weight_real[c];
    block[4 * c + 1] = k.weight_imag[c];
    float* b = &block[4 * (6 + c)];
    b[0] = br.offset, b[1] = br.scale, b[2] = bi.offset, b[3] = bi.scale;
    for (int i = 0; i < k.tap_count(); ++i) {
      float* t = &block[4 * (12 + c * k.tap_count() + i)];
      t[0] = re[i], t[1] = im[i], t[2] = br.taps[i], t[3] = bi.taps[i];
    }
  }
  return block;
}

int checked_max_radius(const FilterOptions& options) {
  const float r = options.pattern.max_radius_px();
  if (r < 1.0f)
    throw std::invalid_argument("circular filters need a max radius k (N - 1) / 2 >= 1 px, got " + std::to_string(r));
  return static_cast<int>(r);
}

// Output pixels per invocation along each pass (spec constant OUTPUTS): every loaded value serves
// that many taps. lavapipe pays far more per storage-buffer load than per multiply-add.
// 4 and 4 measured best on lavapipe at 800x600 (vs 1, 2, 3, 8): 1.5-2.5x faster passes than 1 and 1.
constexpr int kHorizontalOutputs = 4, kVerticalOutputs = 4;

std::vector<std::int32_t> spec(const CircularKernel& k, int layer, int outputs) {
  return {k.components, k.radius_px, layer, outputs};
}

std::vector<VkDescriptorType> buffers(std::uint32_t n) { return std::vector<VkDescriptorType>(n, kBuffer); }

class Circular final : public gpu::GpuFilter {
 public:
  Circular(GpuFrame& frame, const FilterOptions& options, int far_components)
      : Circular(frame, far_components, options.integer("near_components"), checked_max_radius(options),
                 intermediate_precision_from_string(options.precision)) {}

  Circular(GpuFrame& frame, int far_components, int near_components, int max_radius_px, IntermediatePrecision precision)
      : frame_(frame),
        far_kernel_(make_circular_kernel_for_disc(far_components, max_radius_px)),
        near_kernel_(make_circular_kernel_for_disc(near_components, max_radius_px)),
        far_layer_(vk::make_storage_buffer(frame.ctx, pixels() * 16, "circular far layer")),
        near_layer_(vk::make_storage_buffer(frame.ctx, pixels() * 16, "circular near layer")),
        channel_max_(vk::make_storage_buffer(frame.ctx, 8 * sizeof(std::uint32_t), "circular channel maxima")),
        box_(vk::make_storage_buffer(frame.ctx, precision == IntermediatePrecision::bracketed10 ? pixels() * 8 : 16,
                                     "circular box-sum buffer")),
        far_taps_(upload_kernel(far_kernel_)),
        near_taps_(upload_kernel(near_kernel_)),
        layers_(frame.ctx, vk::spirv("circular/layers"), buffers(6), sizeof(PassParams),
                {precision == IntermediatePrecision::bracketed10 ? 1 : 0}),
        far_horizontal_(frame.ctx, vk::spirv(std::string("circular/horizontal_") + to_string(precision)), buffers(kConvolutionBindings), sizeof(PassParams),
                        spec(far_kernel_, kFarLayer, kHorizontalOutputs)),
        far_vertical_(frame.ctx, vk::spirv(std::string("circular/vertical_") + to_string(precision)), buffers(kVerticalBindings), sizeof(PassParams),
                      spec(far_kernel_, kFarLayer, kVerticalOutputs)),
        near_horizontal_(frame.ctx, vk::spirv(std::string("circular/horizontal_") + to_string(precision)), buffers(kConvolutionBindings), sizeof(PassParams),
                         spec(near_kernel_, kNearLayer, kHorizontalOutputs)),
        near_vertical_(frame.ctx, vk::spirv(std::string("circular/vertical_") + to_string(precision)), buffers(kVerticalBindings), sizeof(PassParams),
                       spec(near_kernel_, kNearLayer, kVerticalOutputs)) {
    // Near and far run one after the other, so they share the component buffers.
    const int components = std::max(far_components, near_components);
    for (int c = 0; c < components; ++c)
      inter_.push_back(vk::make_storage_buffer(frame.ctx, pixels() * circular_component_bytes_per_pixel(precision),
                                               ("circular intermediate, component " + std::to_string(c)).c_str()));
    layers_.bind(0, frame.color);
    layers_.bind(1, frame.depth);
    layers_.bind(2, frame.packed);
    layers_.bind(3, far_layer_);
    layers_.bind(4, near_layer_);
    layers_.bind(5, channel_max_);
    bind_convolution(far_horizontal_, far_taps_, far_layer_);
    bind_convolution(far_vertical_, far_taps_, far_layer_);
    bind_convolution(near_horizontal_, near_taps_, near_layer_);
    bind_convolution(near_vertical_, near_taps_, near_layer_);
    for (vk::ComputePipeline* v : {&far_vertical_, &near_vertical_}) {
      v->bind(10, frame.color);
      v->bind(11, frame.output);
    }
  }

  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    // The maxima are reduced with atomicMax: start from 0 every frame.
    vkCmdFillBuffer(cmd, channel_max_.get(), 0, VK_WHOLE_SIZE, 0);
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
    const PassParams* params = &frame_.params;
    const std::uint32_t w = frame_.width(), h = frame_.height();
    layers_.dispatch(cmd, params, w, h);
    timer.end_pass(cmd, "layers");
    far_horizontal_.dispatch(cmd, params, horizontal_invocations(w), h);
    timer.end_pass(cmd, "far_horizontal");
    far_vertical_.dispatch(cmd, params, w, vertical_invocations(h));
    timer.end_pass(cmd, "far_vertical");
    near_horizontal_.dispatch(cmd, params, horizontal_invocations(w), h);
    timer.end_pass(cmd, "near_horizontal");
    near_vertical_.dispatch(cmd, params, w, vertical_invocations(h));
    timer.end_pass(cmd, "near_vertical");
  }

  std::uint64_t intermediate_bytes() const override {
    std::uint64_t bytes = far_layer_.allocated_bytes() + near_layer_.allocated_bytes() +
                          channel_max_.allocated_bytes() + box_.allocated_bytes() + far_taps_.allocated_bytes() +
                          near_taps_.allocated_bytes();
    for (const vk::Buffer& b : inter_) bytes += b.allocated_bytes();
    return bytes;
  }

 private:
  static std::uint32_t horizontal_invocations(std::uint32_t w) {
    return (w + kHorizontalOutputs - 1) / kHorizontalOutputs;
  }
  static std::uint32_t vertical_invocations(std::uint32_t h) { return (h + kVerticalOutputs - 1) / kVerticalOutputs; }
  VkDeviceSize pixels() const { return static_cast<VkDeviceSize>(frame_.width()) * frame_.height(); }

  vk::Buffer upload_kernel(const CircularKernel& k) {
    const std::vector<float> block = kernel_block(k);
    vk::Buffer buffer = vk::make_storage_buffer(frame_.ctx, block.size() * sizeof(float), "circular kernel taps");
    vk::upload(frame_.ctx, buffer, block.data(), block.size() * sizeof(float));
    return buffer;
  }

  void bind_convolution(vk::ComputePipeline& pass, const vk::Buffer& taps, const vk::Buffer& layer) {
    pass.bind(0, taps);
    pass.bind(1, channel_max_);
    pass.bind(2, layer);
    pass.bind(3, box_);
    // Bindings past the component count are never read; they only need a valid buffer.
    for (std::uint32_t c = 0; c < 6; ++c) pass.bind(4 + c, inter_[std::min<std::size_t>(c, inter_.size() - 1)]);
  }

  GpuFrame& frame_;
  CircularKernel far_kernel_, near_kernel_;
  vk::Buffer far_layer_, near_layer_, channel_max_, box_, far_taps_, near_taps_;
  std::vector<vk::Buffer> inter_;
  vk::ComputePipeline layers_, far_horizontal_, far_vertical_, near_horizontal_, near_vertical_;
};

}  // namespace

// See convolution.glsl; equals circular_cost(...).intermediate_bytes_per_pixel per component for 4
// channels (RGBA layers).
std::uint64_t circular_component_bytes_per_pixel(IntermediatePrecision p) {
  switch (p) {
    case IntermediatePrecision::f32: return 32;
    case IntermediatePrecision::f16: return 16;
    case IntermediatePrecision::bracketed10: return 12;
  }
  throw std::invalid_argument("unknown intermediate precision");
}

std::unique_ptr<gpu::GpuFilter> make_circular_gpu(GpuFrame& frame, const FilterOptions& options, int components) {
  return std::make_unique<Circular>(frame, options, components);
}

}  // namespace bokeh
