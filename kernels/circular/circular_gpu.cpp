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
//
// Radius-following mode (adaptive on: circular_blur_adaptive() on the CPU, pass for pass):
//   layers           as above, but the layers hold (rgb, s) with s the bucket coordinate of the
//                    radius, and each field's bucket mask, whole and per 32 x 32 tile, is reduced
//                    (subgroupOr + atomicOr).
//   tiles            tiles.comp lists the tiles each bucket's passes visit (its pixels' tiles spread
//                    by its kernel's reach, shaders/circular/tiles.glsl); `plan` turns the lists'
//                    lengths into the indirect dispatch sizes of every bucket's passes (4 workgroups
//                    a tile; none for an empty list).
//   far              for each bucket k = 1..K of the far field (ascending): a horizontal pass (the
//                    layer's share (rgb, 1) max(0, 1 - |s - k|), bucket k's kernel) and a vertical
//                    pass adding its result to the field's sum, over their tiles; then
//                    composite.comp (far).
//   near             the same for the near field (sum zeroed again), then composite.comp (near).
// Skipped tiles hold exact zeros of the full convolution, so the output is the same as without
// tiles. Each bucket's kernel has its own uniform buffer and pipelines (kernel radius and
// components as specialization constants; a far and a near bucket with the same kernel share
// pipelines); the component buffers are shared by all of them. A field's bucket passes are stamped
// as one pass: the runner reserves timestamps per named pass, and the buckets interleave
// horizontal and vertical passes.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "circular_config.hpp"
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
// layers.comp: colour, depth, packed, far, near, channel maxima; the buckets (uniform); the tile state.
std::vector<VkDescriptorType> layers_bindings() {
  std::vector<VkDescriptorType> b(6, kBuffer);
  b.insert(b.end(), {kUniform, kBuffer});
  return b;
}
std::vector<VkDescriptorType> horizontal_bindings() {
  std::vector<VkDescriptorType> b = convolution_bindings();
  b.push_back(kTexels);
  b.push_back(kBuffer);  // 11: the tile lists (radius-following buckets)
  return b;
}
std::vector<VkDescriptorType> vertical_bindings() {
  std::vector<VkDescriptorType> b = convolution_bindings();
  b.insert(b.end(), {kBuffer, kBuffer});
  b.insert(b.end(), 7, kTexels);
  b.push_back(kBuffer);  // 19: the field's sum (radius-following buckets)
  b.push_back(kBuffer);  // 20: the tile lists
  return b;
}

// The Kernel block of convolution.glsl (std140): weight[6], bracket[6], then taps[c * (2R + 1) + i];
// weight[0].z holds the field (read by bucket passes).
std::vector<float> kernel_block(const CircularKernel& k, int field) {
  std::vector<float> block(4 * (12 + k.components * k.tap_count()), 0.0f);
  block[2] = static_cast<float>(field);
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

int checked_max_radius(const CircularFilterConfig& config) {
  const int r = config.max_radius_px;
  if (r < 1)
    throw std::invalid_argument("circular filters need a max radius k (N - 1) / 2 >= 1 px, got " +
                                std::to_string(static_cast<float>(r)));
  return r;
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

std::vector<std::int32_t> spec(const CircularKernel& k, int layer, int outputs, const CircularPassShape& shape,
                               int bucket = 0, int buckets = 1) {
  return {k.components, k.radius_px, layer,    outputs, shape.texel_loads ? 1 : 0, shape.sliding_window ? 1 : 0,
          bucket,       buckets};
}

// Tiles of the radius-following mode (kTilePx, circular_separable.hpp; shaders/circular/tiles.glsl):
// a tile is one workgroup of kHorizontalOutputs-pixel invocations wide and 4 workgroups high (8 x 8
// invocations each; plan.comp dispatches 1 x 4 workgroups a list entry), and the transpose for the
// vertical pass. Lists: one per field, bucket and pass, their lengths first in the tile state.
constexpr int kListCounts = 4 * 32;
constexpr std::uint32_t kZeroTile = 0x80000000u;  // ZERO_TILE: a horizontal entry that writes zeros
static_assert(kTilePx == 8 * kHorizontalOutputs && kTilePx == 8 * kVerticalOutputs && kTilePx == 4 * 8);
int tile_list_index(int field, int bucket, int pass) { return 2 * (32 * field + bucket - 1) + pass; }

// The Buckets block of layers.comp and tiles.comp (std140): ramp[k] = (scale, offset, 0, 0), then
// reach[k] = (ceil(R / 32) of the far kernel, of the near kernel, 0, 0), k = 0..K-1 for buckets 1..K.
std::vector<std::uint32_t> bucket_block(const CircularBuckets& b, const std::vector<int>& far_radius_px,
                                        const std::vector<int>& near_radius_px) {
  std::vector<std::uint32_t> block(kCircularBucketTableBytes / 4, 0u);
  for (int k = 0; k < b.count(); ++k) {
    block[4 * k] = std::bit_cast<std::uint32_t>(b.ramp_scale[k]);
    block[4 * k + 1] = std::bit_cast<std::uint32_t>(b.ramp_offset[k]);
    if (k < static_cast<int>(far_radius_px.size())) {
      block[4 * (32 + k)] = static_cast<std::uint32_t>((far_radius_px[k] + kTilePx - 1) / kTilePx);
      block[4 * (32 + k) + 1] = static_cast<std::uint32_t>((near_radius_px[k] + kTilePx - 1) / kTilePx);
    }
  }
  return block;
}

// Tap radii of every bucket's kernel of one field.
std::vector<int> bucket_tap_radii(const CircularBuckets& b, int components) {
  std::vector<int> radii;
  for (float disc : b.disc_radius_px) radii.push_back(make_circular_kernel_for_disc(components, disc).radius_px);
  return radii;
}

// Mirrors `Groups` in shaders/circular/plan.comp.
struct PlanGroups {
  std::uint32_t horizontal_x, horizontal_y, vertical_x, vertical_y;
};
// Offsets of the VkDispatchIndirectCommands plan.comp writes (fixed kernel; the radius-following
// mode writes one per tile list, at 16 tile_list_index(f, k, pass)).
constexpr VkDeviceSize kFarHorizontalArgs = 0, kNearHorizontalArgs = 16, kNearVerticalArgs = 32, kArgsBytes = 48;
VkDeviceSize bucket_args(int field, int bucket, int pass) {
  return 16 * static_cast<VkDeviceSize>(tile_list_index(field, bucket, pass));
}
// ChannelMax of convolution.glsl and layers.comp: 8 maxima and 2 bucket masks.
constexpr VkDeviceSize kChannelMaxBytes = 10 * sizeof(std::uint32_t);

// Bucket k's kernel of one field with its uniform buffer and passes.
struct BucketPasses {
  CircularKernel kernel;
  vk::Buffer taps;
  vk::ComputePipeline horizontal, vertical;
};

class Circular final : public gpu::GpuFilter {
 public:
  Circular(GpuFrame& frame, const CircularFilterConfig& config, const CircularPassShape& shape)
      : Circular(frame, config.far_components, config.near_components, checked_max_radius(config), config.precision,
                 config.adaptive, shape) {}

  Circular(GpuFrame& frame, int far_components, int near_components, int max_radius_px,
           IntermediatePrecision precision, bool adaptive, const CircularPassShape& shape)
      : frame_(frame),
        adaptive_(adaptive),
        buckets_(circular_buckets(max_radius_px)),
        far_layer_(make_texel_buffer(pixels() * 16, "circular far layer")),
        near_layer_(make_texel_buffer(pixels() * 16, "circular near layer")),
        channel_max_(vk::make_storage_buffer(frame.ctx, kChannelMaxBytes, "circular channel maxima")),
        box_(make_texel_buffer(precision == IntermediatePrecision::bracketed10 ? pixels() * 8 : 16,
                               "circular box-sum buffer")),
        field_sum_(vk::make_storage_buffer(frame.ctx, adaptive ? pixels() * 16 : 16, "circular field sum")),
        dispatch_args_(vk::make_storage_buffer(frame.ctx, adaptive ? 16 * kListCounts : kArgsBytes,
                                               "circular dispatch sizes", VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)),
        bucket_ramps_(upload_uniform(bucket_block(buckets_, bucket_tap_radii(buckets_, far_components),
                                                  bucket_tap_radii(buckets_, near_components)),
                                     "circular buckets")),
        tile_state_(vk::make_storage_buffer(frame.ctx, adaptive ? 4 * (kListCounts + 4 * tiles()) : 16,
                                            "circular tile state")),
        tile_lists_(vk::make_storage_buffer(frame.ctx,
                                            adaptive ? 4 * (tile_list_index(1, buckets_.count(), 1) + 1) * tiles() : 16,
                                            "circular tile lists")),
        far_layer_texels_(frame.ctx, far_layer_, VK_FORMAT_R32G32B32A32_SFLOAT, 16, "circular far layer"),
        near_layer_texels_(frame.ctx, near_layer_, VK_FORMAT_R32G32B32A32_SFLOAT, 16, "circular near layer"),
        box_texels_(frame.ctx, box_, VK_FORMAT_R32G32_UINT, 8, "circular box-sum buffer"),
        layers_(frame.ctx, vk::spirv("circular/layers"), layers_bindings(), sizeof(PassParams),
                {precision == IntermediatePrecision::bracketed10 ? 1 : 0, adaptive ? 1 : 0, buckets_.count()}),
        plan_(frame.ctx, vk::spirv("circular/plan"), {kBuffer, kBuffer, kBuffer}, sizeof(PlanGroups),
              {adaptive ? 1 : 0, buckets_.count()}),
        tile_rows_(frame.ctx, vk::spirv("circular/tiles"), {kBuffer, kBuffer, kUniform}, sizeof(PassParams),
                   {0, buckets_.count()}),
        tile_columns_(frame.ctx, vk::spirv("circular/tiles"), {kBuffer, kBuffer, kUniform}, sizeof(PassParams),
                      {1, buckets_.count()}) {
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
    layers_.bind(6, bucket_ramps_);
    layers_.bind(7, tile_state_);
    plan_.bind(0, channel_max_);
    plan_.bind(1, dispatch_args_);
    plan_.bind(2, tile_state_);
    for (vk::ComputePipeline* t : {&tile_rows_, &tile_columns_}) {
      t->bind(0, tile_state_);
      t->bind(1, tile_lists_);
      t->bind(2, bucket_ramps_);
    }
    const std::string horizontal = std::string("circular/horizontal_") + to_string(precision);
    const std::string vertical = std::string("circular/vertical_") + to_string(precision);
    for (int field : {kFarLayer, kNearLayer}) {
      const int n = field == kFarLayer ? far_components : near_components;
      const vk::Buffer& layer = field == kFarLayer ? far_layer_ : near_layer_;
      const vk::TexelView& layer_texels = field == kFarLayer ? far_layer_texels_ : near_layer_texels_;
      // Fixed: one kernel at the max radius (bucket 0); radius-following: one per bucket.
      std::vector<std::pair<int, float>> kernels = {{0, static_cast<float>(max_radius_px)}};
      if (adaptive) {
        kernels.clear();
        for (int k = 1; k <= buckets_.count(); ++k) kernels.push_back({k, buckets_.disc_radius_px[k - 1]});
      }
      for (const auto& [bucket, disc] : kernels) {
        CircularKernel kernel = make_circular_kernel_for_disc(n, disc);
        vk::Buffer taps = upload_uniform(kernel_block(kernel, field), "circular kernel taps");
        // Buckets take their field from the kernel block: far and near share equal pipelines.
        const int spec_layer = bucket > 0 ? 0 : field;
        const auto horizontal_spec = spec(kernel, spec_layer, kHorizontalOutputs, shape, bucket, buckets_.count());
        const auto vertical_spec = spec(kernel, spec_layer, kVerticalOutputs, shape, bucket, buckets_.count());
        auto passes = std::make_unique<BucketPasses>(BucketPasses{
            std::move(kernel), std::move(taps),
            vk::ComputePipeline(frame.ctx, vk::spirv(horizontal), horizontal_bindings(), sizeof(PassParams),
                                horizontal_spec),
            vk::ComputePipeline(frame.ctx, vk::spirv(vertical), vertical_bindings(), sizeof(PassParams),
                                vertical_spec)});
        bind_convolution(passes->horizontal, passes->taps, layer);
        bind_convolution(passes->vertical, passes->taps, layer);
        passes->horizontal.bind(10, layer_texels);
        passes->horizontal.bind(11, tile_lists_);
        passes->vertical.bind(10, frame.color);
        passes->vertical.bind(11, frame.output);
        // Bindings past the component count are never read; they only need a valid view.
        for (std::uint32_t c = 0; c < 6; ++c)
          passes->vertical.bind(12 + c, inter_texels_[std::min<std::size_t>(c, inter_.size() - 1)]);
        passes->vertical.bind(18, box_texels_);
        passes->vertical.bind(19, field_sum_);
        passes->vertical.bind(20, tile_lists_);
        fields_[field].push_back(std::move(passes));
      }
      if (adaptive) {
        auto composite = std::make_unique<vk::ComputePipeline>(
            frame.ctx, vk::spirv("circular/composite"), std::vector<VkDescriptorType>(5, kBuffer),
            sizeof(PassParams), std::vector<std::int32_t>{field});
        composite->bind(0, frame.color);
        composite->bind(1, far_layer_);
        composite->bind(2, near_layer_);
        composite->bind(3, field_sum_);
        composite->bind(4, frame.output);
        composites_[field] = std::move(composite);
      }
    }
  }

  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    // The maxima are reduced with atomicMax (the masks with atomicOr), the tile lists counted with
    // atomicAdd: start from 0 every frame.
    fill_zero(cmd, channel_max_);
    if (adaptive_) fill_zero(cmd, tile_state_);
    const PassParams* params = &frame_.params;
    const std::uint32_t w = frame_.width(), h = frame_.height();
    layers_.dispatch(cmd, params, w, h);
    const BucketPasses& first = *fields_[kFarLayer].front();
    const VkDispatchIndirectCommand hg = first.horizontal.groups(horizontal_invocations(w), h);
    const VkDispatchIndirectCommand vg = first.vertical.groups(w, vertical_invocations(h));
    const PlanGroups groups{hg.x, hg.y, vg.x, vg.y};
    if (adaptive_) {
      timer.end_pass(cmd, "layers");
      const std::uint32_t columns = (w + kTilePx - 1) / kTilePx, rows = (h + kTilePx - 1) / kTilePx;
      tile_rows_.dispatch(cmd, params, columns, rows);
      tile_columns_.dispatch(cmd, params, columns, rows);
      plan_.dispatch(cmd, &groups, 1, 1);
      timer.end_pass(cmd, "tiles");
      for (int field : {kFarLayer, kNearLayer}) {
        fill_zero(cmd, field_sum_);
        for (int k = 1; k <= buckets_.count(); ++k) {
          const BucketPasses& b = *fields_[field][k - 1];
          b.horizontal.dispatch_indirect(cmd, params, dispatch_args_, bucket_args(field, k, 0));
          b.vertical.dispatch_indirect(cmd, params, dispatch_args_, bucket_args(field, k, 1));
        }
        composites_[field]->dispatch(cmd, params, w, h);
        timer.end_pass(cmd, field == kFarLayer ? "far" : "near");
      }
      return;
    }
    plan_.dispatch(cmd, &groups, 1, 1);
    timer.end_pass(cmd, "layers");
    const BucketPasses& far = *fields_[kFarLayer].front();
    const BucketPasses& near = *fields_[kNearLayer].front();
    far.horizontal.dispatch_indirect(cmd, params, dispatch_args_, kFarHorizontalArgs);
    timer.end_pass(cmd, "far_horizontal");
    far.vertical.dispatch(cmd, params, w, vertical_invocations(h));
    timer.end_pass(cmd, "far_vertical");
    near.horizontal.dispatch_indirect(cmd, params, dispatch_args_, kNearHorizontalArgs);
    timer.end_pass(cmd, "near_horizontal");
    near.vertical.dispatch_indirect(cmd, params, dispatch_args_, kNearVerticalArgs);
    timer.end_pass(cmd, "near_vertical");
  }

  std::uint64_t intermediate_bytes() const override {
    std::uint64_t bytes = far_layer_.allocated_bytes() + near_layer_.allocated_bytes() +
                          channel_max_.allocated_bytes() + box_.allocated_bytes() + dispatch_args_.allocated_bytes() +
                          bucket_ramps_.allocated_bytes();
    if (adaptive_)
      bytes += field_sum_.allocated_bytes() + tile_state_.allocated_bytes() + tile_lists_.allocated_bytes();
    for (const auto& field : fields_)
      for (const auto& b : field) bytes += b->taps.allocated_bytes();
    for (const vk::Buffer& b : inter_) bytes += b.allocated_bytes();
    return bytes;
  }

  // Radius-following: the buckets and tiles the last frame ran (its masks and tile lists, read back).
  nlohmann::json stats() override {
    if (!adaptive_) return nlohmann::json::object();
    std::uint32_t words[10] = {};
    vk::download(frame_.ctx, channel_max_, words, sizeof words);
    const int w = static_cast<int>(frame_.width()), h = static_cast<int>(frame_.height());
    const int columns = (w + kTilePx - 1) / kTilePx, rows = (h + kTilePx - 1) / kTilePx, tiles = columns * rows;
    std::vector<std::uint32_t> counts(kListCounts);
    std::vector<std::uint32_t> lists(static_cast<std::size_t>(tile_list_index(1, buckets_.count(), 1) + 1) * tiles);
    vk::download(frame_.ctx, tile_state_, counts.data(), counts.size() * 4);
    vk::download(frame_.ctx, tile_lists_, lists.data(), lists.size() * 4);
    AdaptiveWork work;
    work.tiles = tiles;
    for (int f = 0; f < 2; ++f) {
      work.bucket_mask[f] = words[8 + f];
      for (int k = 1; k <= buckets_.count(); ++k) {
        const CircularKernel& kernel = fields_[f][k - 1]->kernel;
        const double taps = kernel.components * (2.0 * kernel.radius_px + 1);
        int computed = 0, zeroed = 0, vertical = 0;
        for (int pass = 0; pass < 2; ++pass) {
          const int list = tile_list_index(f, k, pass);
          for (std::uint32_t e = 0; e < counts[list]; ++e) {
            const std::uint32_t entry = lists[static_cast<std::size_t>(list) * tiles + e];
            const int t = static_cast<int>(entry & ~kZeroTile);
            const double pixels = static_cast<double>(std::min(kTilePx, w - (t % columns) * kTilePx)) *
                                  std::min(kTilePx, h - (t / columns) * kTilePx);
            int& count = pass == 1 ? vertical : (entry & kZeroTile) ? zeroed : computed;
            ++count;
            if (pass == 1 || !(entry & kZeroTile)) work.taps[f] += pixels * taps;
          }
        }
        work.horizontal_tiles[f].push_back(computed);
        work.zero_tiles[f].push_back(zeroed);
        work.vertical_tiles[f].push_back(vertical);
      }
    }
    return bucket_stats(buckets_, work);
  }

 private:
  static std::uint32_t horizontal_invocations(std::uint32_t w) {
    return (w + kHorizontalOutputs - 1) / kHorizontalOutputs;
  }
  static std::uint32_t vertical_invocations(std::uint32_t h) { return (h + kVerticalOutputs - 1) / kVerticalOutputs; }
  VkDeviceSize pixels() const { return static_cast<VkDeviceSize>(frame_.width()) * frame_.height(); }
  VkDeviceSize tiles() const {
    return static_cast<VkDeviceSize>((frame_.width() + kTilePx - 1) / kTilePx) *
           ((frame_.height() + kTilePx - 1) / kTilePx);
  }

  vk::Buffer make_texel_buffer(VkDeviceSize bytes, const char* what) {
    return vk::make_storage_buffer(frame_.ctx, bytes, what, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT);
  }

  template <class T>
  vk::Buffer upload_uniform(const std::vector<T>& block, const char* what) {
    vk::Buffer buffer = vk::make_uniform_buffer(frame_.ctx, block.size() * sizeof(T), what);
    vk::upload(frame_.ctx, buffer, block.data(), block.size() * sizeof(T));
    return buffer;
  }

  // Zeroes `buffer` once every earlier pass is done with it, before any later pass uses it.
  static void fill_zero(VkCommandBuffer cmd, const vk::Buffer& buffer) {
    vkCmdFillBuffer(cmd, buffer.get(), 0, VK_WHOLE_SIZE, 0);
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
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
  bool adaptive_;
  CircularBuckets buckets_;
  vk::Buffer far_layer_, near_layer_, channel_max_, box_, field_sum_, dispatch_args_, bucket_ramps_, tile_state_,
      tile_lists_;
  vk::TexelView far_layer_texels_, near_layer_texels_, box_texels_;
  std::vector<vk::Buffer> inter_;
  std::vector<vk::TexelView> inter_texels_;
  vk::ComputePipeline layers_, plan_, tile_rows_, tile_columns_;
  // Per field (far, near): one kernel's passes (fixed) or one per bucket (radius-following).
  std::vector<std::unique_ptr<BucketPasses>> fields_[2];
  std::unique_ptr<vk::ComputePipeline> composites_[2];
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
  return std::make_unique<Circular>(frame, circular_config(options, components),
                                    shape.value_or(circular_pass_shape_for(frame.ctx.info())));
}

}  // namespace bokeh
