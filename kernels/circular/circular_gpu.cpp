// GPU circular separable convolution depth of field (Garcia, GDC 2018): circular_blur() of
// kernels/circular/circular_separable.cpp on the GPU, pass for pass and in the same arithmetic order.
//   layers           colour + packed radius + depth -> near and far RGBA layers (rgb w, w), with
//                    w = clamp(radius / max radius, 0, 1), and the per-channel maxima of each layer (a
//                    GPU reduction: subgroupMax + atomicMax, zeroed by a fill first): alpha always (an
//                    empty field has alpha max 0), colour for bracketed10. Then `plan` (one
//                    invocation, timed with layers) turns emptiness into the indirect dispatch sizes
//                    of the passes below: an empty field is skipped without a read-back, as the CPU
//                    reference skips it.
//   far_horizontal   per far component c, the complex response H_c of each RGBA channel, stored f32,
//                    f16 or bracketed 10-bit (+ the f16 box sum), one storage buffer per component.
//   far_vertical     V_c = vertical complex convolution of H_c, b = sum_c A_c Re V_c + B_c Im V_c,
//                    composited over the sharp colour with the pixel's own far alpha -> output.
//   near_horizontal  as far, with the near layer and the near component count (same buffers, reused).
//   near_vertical    as far; composited over the far result with alpha = clamp(b.a, 0, 1) -> output.
// Both kernels are make_circular_kernel_for_disc(components, max radius): the disc radius is the
// pattern's max radius k (N - 1) / 2. Taps, weights and the bracketing constants O, S are computed on
// the CPU exactly as the reference does and uploaded once, to a uniform buffer; kernel radius and
// component count are specialization constants. Each invocation of a horizontal (vertical) pass
// computes 4 adjacent pixels of a row (column), so every value it loads serves up to 4 taps; each
// output still sums its taps in the CPU's order. The subgroup reduction needs
// VK_SUBGROUP_FEATURE_ARITHMETIC_BIT in compute (lavapipe and desktop drivers have it).
#include <algorithm>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "circular_gpu.hpp"
#include "circular_separable.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

using gpu::GpuFrame;
using gpu::PassParams;

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
constexpr VkDescriptorType kUniform = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
constexpr VkDescriptorType kTexels = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
constexpr int kFarLayer = 0, kNearLayer = 1;

// Bindings of convolution.glsl: kernel (uniform), channel maxima, layer, box sum, 6 component
// buffers; the horizontal pass adds the layer as texels, the vertical pass colour, output, the 6
// component buffers and the box sums as texels.
std::vector<VkDescriptorType> convolution_bindings() {
  std::vector<VkDescriptorType> b(10, kBuffer);
  b[0] = kUniform;
  return b;
}
std::vector<VkDescriptorType> horizontal_bindings() {
  std::vector<VkDescriptorType> b = convolution_bindings();
  b.push_back(kTexels);
  return b;
}
std::vector<VkDescriptorType> vertical_bindings() {
  std::vector<VkDescriptorType> b = convolution_bindings();
  b.insert(b.end(), {kBuffer, kBuffer});
  b.insert(b.end(), 7, kTexels);
  return b;
}

// The Kernel block of convolution.glsl (std140): weight[6], bracket[6], then taps[c * (2R + 1) + i].
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
// that many taps. 4 and 4 measured best on lavapipe at 800x600 (vs 1, 2, 3, 8, and 16 for the
// horizontal pass with the sliding window).
constexpr int kHorizontalOutputs = 4, kVerticalOutputs = 4;

// How each intermediate is read as texels (TEXEL_LOADS): f32 two RGBA32F texels a pixel, f16 one
// RGBA32UI (four packHalf2x16 words), bracketed10 three R32UI; the box sums one RG32UI.
struct TexelFormat {
  VkFormat format;
  std::uint32_t bytes;
};
TexelFormat intermediate_texels(IntermediatePrecision p) {
  switch (p) {
    case IntermediatePrecision::f32: return {VK_FORMAT_R32G32B32A32_SFLOAT, 16};
    case IntermediatePrecision::f16: return {VK_FORMAT_R32G32B32A32_UINT, 16};
    case IntermediatePrecision::bracketed10: return {VK_FORMAT_R32_UINT, 4};
  }
  throw std::invalid_argument("unknown intermediate precision");
}

std::vector<std::int32_t> spec(const CircularKernel& k, int layer, int outputs, const CircularPassShape& shape) {
  return {k.components, k.radius_px, layer, outputs, shape.texel_loads ? 1 : 0, shape.sliding_window ? 1 : 0};
}

// Mirrors `Groups` in shaders/circular/plan.comp.
struct PlanGroups {
  std::uint32_t horizontal_x, horizontal_y, vertical_x, vertical_y;
};
// Offsets of the VkDispatchIndirectCommands plan.comp writes.
constexpr VkDeviceSize kFarHorizontalArgs = 0, kNearHorizontalArgs = 16, kNearVerticalArgs = 32, kArgsBytes = 48;

class Circular final : public gpu::GpuFilter {
 public:
  Circular(GpuFrame& frame, const FilterOptions& options, int far_components, const CircularPassShape& shape)
      : Circular(frame, far_components, options.integer("near_components"), checked_max_radius(options),
                 intermediate_precision_from_string(options.precision), shape) {}

  Circular(GpuFrame& frame, int far_components, int near_components, int max_radius_px,
           IntermediatePrecision precision, const CircularPassShape& shape)
      : frame_(frame),
        far_kernel_(make_circular_kernel_for_disc(far_components, max_radius_px)),
        near_kernel_(make_circular_kernel_for_disc(near_components, max_radius_px)),
        far_layer_(make_texel_buffer(pixels() * 16, "circular far layer")),
        near_layer_(make_texel_buffer(pixels() * 16, "circular near layer")),
        channel_max_(vk::make_storage_buffer(frame.ctx, 8 * sizeof(std::uint32_t), "circular channel maxima")),
        box_(make_texel_buffer(precision == IntermediatePrecision::bracketed10 ? pixels() * 8 : 16,
                               "circular box-sum buffer")),
        dispatch_args_(vk::make_storage_buffer(frame.ctx, kArgsBytes, "circular dispatch sizes",
                                               VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)),
        far_taps_(upload_kernel(far_kernel_)),
        near_taps_(upload_kernel(near_kernel_)),
        far_layer_texels_(frame.ctx, far_layer_, VK_FORMAT_R32G32B32A32_SFLOAT, 16, "circular far layer"),
        near_layer_texels_(frame.ctx, near_layer_, VK_FORMAT_R32G32B32A32_SFLOAT, 16, "circular near layer"),
        box_texels_(frame.ctx, box_, VK_FORMAT_R32G32_UINT, 8, "circular box-sum buffer"),
        layers_(frame.ctx, vk::spirv("circular/layers"), std::vector<VkDescriptorType>(6, kBuffer), sizeof(PassParams),
                {precision == IntermediatePrecision::bracketed10 ? 1 : 0}),
        plan_(frame.ctx, vk::spirv("circular/plan"), {kBuffer, kBuffer}, sizeof(PlanGroups)),
        far_horizontal_(frame.ctx, vk::spirv(std::string("circular/horizontal_") + to_string(precision)),
                        horizontal_bindings(), sizeof(PassParams),
                        spec(far_kernel_, kFarLayer, kHorizontalOutputs, shape)),
        far_vertical_(frame.ctx, vk::spirv(std::string("circular/vertical_") + to_string(precision)),
                      vertical_bindings(), sizeof(PassParams), spec(far_kernel_, kFarLayer, kVerticalOutputs, shape)),
        near_horizontal_(frame.ctx, vk::spirv(std::string("circular/horizontal_") + to_string(precision)),
                         horizontal_bindings(), sizeof(PassParams),
                         spec(near_kernel_, kNearLayer, kHorizontalOutputs, shape)),
        near_vertical_(frame.ctx, vk::spirv(std::string("circular/vertical_") + to_string(precision)),
                       vertical_bindings(), sizeof(PassParams), spec(near_kernel_, kNearLayer, kVerticalOutputs, shape)) {
    // Near and far run one after the other, so they share the component buffers.
    const int components = std::max(far_components, near_components);
    const TexelFormat texels = intermediate_texels(precision);
    for (int c = 0; c < components; ++c) {
      const std::string what = "circular intermediate, component " + std::to_string(c);
      inter_.push_back(make_texel_buffer(pixels() * circular_component_bytes_per_pixel(precision), what.c_str()));
      inter_texels_.emplace_back(frame.ctx, inter_.back(), texels.format, texels.bytes, what.c_str());
    }
    layers_.bind(0, frame.color);
    layers_.bind(1, frame.depth);
    layers_.bind(2, frame.packed);
    layers_.bind(3, far_layer_);
    layers_.bind(4, near_layer_);
    layers_.bind(5, channel_max_);
    plan_.bind(0, channel_max_);
    plan_.bind(1, dispatch_args_);
    bind_convolution(far_horizontal_, far_taps_, far_layer_);
    bind_convolution(far_vertical_, far_taps_, far_layer_);
    bind_convolution(near_horizontal_, near_taps_, near_layer_);
    bind_convolution(near_vertical_, near_taps_, near_layer_);
    far_horizontal_.bind(10, far_layer_texels_);
    near_horizontal_.bind(10, near_layer_texels_);
    for (vk::ComputePipeline* v : {&far_vertical_, &near_vertical_}) {
      v->bind(10, frame.color);
      v->bind(11, frame.output);
      // Bindings past the component count are never read; they only need a valid view.
      for (std::uint32_t c = 0; c < 6; ++c) v->bind(12 + c, inter_texels_[std::min<std::size_t>(c, inter_.size() - 1)]);
      v->bind(18, box_texels_);
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
    const VkDispatchIndirectCommand hg = far_horizontal_.groups(horizontal_invocations(w), h);
    const VkDispatchIndirectCommand vg = near_vertical_.groups(w, vertical_invocations(h));
    const PlanGroups groups{hg.x, hg.y, vg.x, vg.y};
    plan_.dispatch(cmd, &groups, 1, 1);
    timer.end_pass(cmd, "layers");
    far_horizontal_.dispatch_indirect(cmd, params, dispatch_args_, kFarHorizontalArgs);
    timer.end_pass(cmd, "far_horizontal");
    far_vertical_.dispatch(cmd, params, w, vertical_invocations(h));
    timer.end_pass(cmd, "far_vertical");
    near_horizontal_.dispatch_indirect(cmd, params, dispatch_args_, kNearHorizontalArgs);
    timer.end_pass(cmd, "near_horizontal");
    near_vertical_.dispatch_indirect(cmd, params, dispatch_args_, kNearVerticalArgs);
    timer.end_pass(cmd, "near_vertical");
  }

  std::uint64_t intermediate_bytes() const override {
    std::uint64_t bytes = far_layer_.allocated_bytes() + near_layer_.allocated_bytes() +
                          channel_max_.allocated_bytes() + box_.allocated_bytes() + dispatch_args_.allocated_bytes() +
                          far_taps_.allocated_bytes() + near_taps_.allocated_bytes();
    for (const vk::Buffer& b : inter_) bytes += b.allocated_bytes();
    return bytes;
  }

 private:
  static std::uint32_t horizontal_invocations(std::uint32_t w) {
    return (w + kHorizontalOutputs - 1) / kHorizontalOutputs;
  }
  static std::uint32_t vertical_invocations(std::uint32_t h) { return (h + kVerticalOutputs - 1) / kVerticalOutputs; }
  VkDeviceSize pixels() const { return static_cast<VkDeviceSize>(frame_.width()) * frame_.height(); }

  vk::Buffer make_texel_buffer(VkDeviceSize bytes, const char* what) {
    return vk::make_storage_buffer(frame_.ctx, bytes, what, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT);
  }

  vk::Buffer upload_kernel(const CircularKernel& k) {
    const std::vector<float> block = kernel_block(k);
    vk::Buffer buffer = vk::make_uniform_buffer(frame_.ctx, block.size() * sizeof(float), "circular kernel taps");
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
  vk::Buffer far_layer_, near_layer_, channel_max_, box_, dispatch_args_, far_taps_, near_taps_;
  vk::TexelView far_layer_texels_, near_layer_texels_, box_texels_;
  std::vector<vk::Buffer> inter_;
  std::vector<vk::TexelView> inter_texels_;
  vk::ComputePipeline layers_, plan_, far_horizontal_, far_vertical_, near_horizontal_, near_vertical_;
};

}  // namespace

// Why these two choices exist, and why per device. Measured here (lavapipe, 2 shared cores,
// 800x600, circular1, N = 41, k = 2, medians of interleaved frames, each choice alone against
// neither): texel loads 1.3x on the horizontal and 1.6x on the vertical passes, the sliding window
// 1.3x and 1.2x, both together 1.8x and 2.4x.
//   texel_loads: lavapipe (Mesa 22.3) turns a storage-buffer load inside the tap loop (non-uniform
//     control flow) into a loop over the 8 SIMD lanes with a bounds test and a branch per lane and
//     component; texelFetch of a 16-byte texel is one vector gather and a transpose. A GPU (NVIDIA)
//     serves plain 16-byte loads at the full L1 rate and texel fetches through the texture units at
//     a lower one, so GPUs keep the storage-buffer loads the previous implementation made (not
//     measured here: no GPU was lent).
//   sliding_window: on lavapipe a kernel tap read at a loop-varying index is a gather of 8 scalar
//     loads; keeping the OUTPUTS inputs of a tap in registers lets every tap load one input and one
//     kernel tap per component instead of OUTPUTS taps. On a GPU a tap is one broadcast from the
//     constant cache, and the window costs 8 OUTPUTS more live floats per component (192 at 6
//     components): register spills there.
CircularPassShape circular_pass_shape_for(const vk::DeviceInfo& device) {
  const bool software = device.is_software();
  return {software, software};
}

std::uint64_t circular_component_bytes_per_pixel(IntermediatePrecision p) {
  switch (p) {
    case IntermediatePrecision::f32: return 32;
    case IntermediatePrecision::f16: return 16;
    case IntermediatePrecision::bracketed10: return 12;
  }
  throw std::invalid_argument("unknown intermediate precision");
}

std::uint64_t circular_kernel_block_bytes(const CircularKernel& k) {
  return 16 * (12 + static_cast<std::uint64_t>(k.components) * k.tap_count());
}

std::unique_ptr<gpu::GpuFilter> make_circular_gpu(GpuFrame& frame, const FilterOptions& options, int components,
                                                  std::optional<CircularPassShape> shape) {
  return std::make_unique<Circular>(frame, options, components,
                                    shape.value_or(circular_pass_shape_for(frame.ctx.info())));
}

}  // namespace bokeh
