// GPU FLAG: horizontal pass into a 3D storage image (ceil(N/2) layers), vertical pass out.
// A 3D image rather than a buffer: lavapipe's storage buffers stop at 128 MiB, and the paper's
// 1080p/41x41 buffer is 332 MiB.
//
// The horizontal pass computes horizontal_block pixels per invocation at stride k (flag_gpu.hpp):
// each loaded row sample serves them all, with the same layers bit for bit; horizontal_bins picks how
// a sample lands in its layer's bin (indexed or masked, flag_gpu.hpp), again with the same layers, or
// sums each layer by a prefix scan along row segments (scan: horizontal_scan.comp, its own order).
//
// Layer precisions (LayerPrecision, kernels/flag/flag.hpp): one image format and one shader pair each.
// The bracketed ones add a "bracket" pass before the horizontal pass: the horizontal computation
// without the 3D-buffer writes, reducing each (row, layer, channel) to its min and max with
// atomicMin/atomicMax on the float bits (shaders/flag/bracket.comp) into a small storage buffer
// (2 x rows x layers uvec4, reset by vkCmdFillBuffer in the same pass); the horizontal pass
// stores (v - min) / (max - min) in the unorm format and the vertical pass reads min + (max - min) q.
//
// FilterOptions::buffer_scale s > 1 (kernels/flag/flag_reduced.hpp): "downsample" packs the full-res
// colour and CoC into a ceil(W/s) x ceil(H/s) FLAG input for the low-res pattern, FLAG runs there
// into a ceil(L/s)-layer buffer, and "upsample" adds the bilinear low-res result to the sharp part of
// each full-res pixel. Passes, each timed: downsample (s > 1), bracket (bracketed), horizontal,
// vertical, upsample (s > 1).
//
// adaptive = on (coc_tiles_gpu.hpp, kernels/core/coc_tiles.hpp): when the filter is made, the CoC
// pass, the downsample and the tile-max CoC map run once and the scene's largest disc index on FLAG's
// grid comes back (4 bytes): the 3D buffer gets the layers that disc reaches, not ceil(N/2). Every
// frame then computes the tile map (tile_max, tile_reach, tile_layers) before the FLAG passes, which
// bound their row samples, the layers they write and the rows they sum by it; tiles nothing blurred
// reaches pass their input through (shaders/flag/horizontal.comp, vertical.comp).
#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>

#include <fmt/format.h>

#include "ceil_div.hpp"
#include "coc_tiles_gpu.hpp"
#include "flag_config.hpp"
#include "flag_gpu.hpp"
#include "flag_reduced.hpp"
#include "flag_tiles.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

using gpu::GpuFrame;
using gpu::PassParams;

VkFormat layer_format(LayerPrecision precision) {
  switch (precision) {
    case LayerPrecision::f32: return VK_FORMAT_R32G32B32A32_SFLOAT;
    case LayerPrecision::f16: return VK_FORMAT_R16G16B16A16_SFLOAT;
    case LayerPrecision::r11g11b10f: return VK_FORMAT_B10G11R11_UFLOAT_PACK32;
    case LayerPrecision::unorm10_bracketed: return VK_FORMAT_A2B10G10R10_UNORM_PACK32;
    case LayerPrecision::unorm16_bracketed: return VK_FORMAT_R16G16B16A16_UNORM;
  }
  throw std::invalid_argument("layer_format: unknown layer precision");
}

std::uint64_t flag_bracket_buffer_bytes(std::uint32_t rows, std::uint32_t layers) {
  return 2ull * rows * layers * 4 * sizeof(std::uint32_t);  // min and max blocks of uvec4 (rgb, unused)
}

const std::vector<std::string>& flag_horizontal_blocks() {
  static const std::vector<std::string> blocks = {"auto", "1", "2", "4", "8"};
  return blocks;
}

// lavapipe (Mesa 22.3.6) computes wrong FLAG layers, all zero or NaN and without an error, once a
// pass's private arrays grow past what it handles. Measured with single lights at k = 1 (`bokehbench
// stability` found it): the horizontal pass fails at block x layers = 404 (N = 201, block 4) and works
// at 324 (N = 161, block 4) and 202 (N = 201, block 2); the bracket pass of the bracketed precisions
// (four arrays of ceil(N/2) entries) fails at 41 layers (N = 81) and works at 31. On lavapipe, auto
// takes the largest block within the bound and a configuration beyond either bound is refused.
constexpr int kSoftwareMaxBlockLayers = kFlagSoftwareMaxBlockLayers, kSoftwareMaxBracketedLayers = 31;

int flag_horizontal_block(std::optional<int> requested, const vk::DeviceInfo& device, int layers) {
  if (requested) return *requested;
  if (!device.is_software()) return 1;
  for (int block : {4, 2})
    if (block * layers <= kSoftwareMaxBlockLayers) return block;
  return 1;
}

const std::vector<std::string>& flag_vertical_orders() {
  static const std::vector<std::string> orders = {"auto", "rows", "columns"};
  return orders;
}

// lavapipe, 800x600 hoops, k = 2, f16 (`bokehbench ab`, the two orders as two builds, paired rounds,
// wall time): FLAG's frame 0.964x [0.947, 0.992] with columns at N = 153 and 0.961x [0.907, 1.009] at
// N = 81, the vertical pass about 13% faster; see the README for the same within one run.
FlagVerticalOrder flag_vertical_ordering(FlagVerticalOrder order, const vk::DeviceInfo& device) {
  if (order != FlagVerticalOrder::automatic) return order;
  return device.is_software() ? FlagVerticalOrder::columns : FlagVerticalOrder::rows;
}

const std::vector<std::string>& flag_horizontal_bins() {
  static const std::vector<std::string> bins = {"auto", "indexed", "masked", "scan"};
  return bins;
}

// Masked bins pay off on lavapipe only while its compiler unrolls the loop over the bins, so that
// each bin is a register: measured at 800x600, k = 2, block 4, the horizontal pass took 67 vs 89 ms
// (masked vs indexed) at N = 41 and 115 vs 124 ms at N = 63 (32 layers), then 898 vs 120 ms at N = 65
// (33 layers): past 32 iterations (Mesa's usual max_unroll_iterations) the loop stays a loop and
// every bin access becomes the per-lane array access masking was meant to avoid.
// Scan against the others on lavapipe, the same frames interleaved (800x600 hoops, k = 2, f16, the
// horizontal pass's median over 7 rounds, on a loaded machine whose times spread up to 2x; ratios to
// indexed): N = 21 masked 0.63, scan 0.78; N = 41 masked 0.77, scan 0.71; N = 81 masked 8.9, scan
// 0.84; N = 121 scan 0.71. Lavapipe turns each event into a per-lane scalar read and write of the
// difference array, as it does each indexed bin, and a pixel takes about as many events (2 per layer)
// as samples (N). Since the scan's lanes hand samples on by shuffle (one load a sample, not 8) and
// clear only the segment's columns within the frame, masked only up to 12 layers, at any width.
// `bokehbench ab`, auto built as scan against auto built as masked, alone on a 2-core AMD EPYC at
// 2.6 GHz, FLAG frame in process CPU time, scan / masked [95%] (results/scan_shuffle/ab_auto_cleared_*.json):
// - 800x600: N = 17 1.194 [1.171, 1.208]; 21 1.084 [1.078, 1.102]; 25 0.955 [0.948, 0.959];
// - 400x300: N = 29 0.880 [0.869, 0.903]; 41 0.868 [0.858, 0.889]; 57 0.712 [0.705, 0.723];
// - 200x150: N = 17 1.216 [1.139, 1.232]; 21 1.075 [1.055, 1.157]; 25 0.944 [0.923, 0.994]; 29 0.840
//   [0.819, 0.859]; 41 0.812 [0.784, 0.857]; 57 0.686 [0.667, 0.695].
// (Clearing the whole segment had made the scan up to 1.15x masked's time in 200 px rows at N = 29-41.)
constexpr int kSoftwareMaskedFirstLayers = 12;

FlagHorizontalBins flag_horizontal_binning(FlagHorizontalBins bins, const vk::DeviceInfo& device, int layers) {
  if (bins != FlagHorizontalBins::automatic) return bins;
  // A GPU's L1 cache serves the indexed bins (a register file or cache line per pixel) at one add
  // per sample; the scan's re-reads of each sample per group of 8 layers would only add loads there.
  if (!device.is_software()) return FlagHorizontalBins::indexed;
  if (layers <= kSoftwareMaskedFirstLayers) return FlagHorizontalBins::masked;
  return device.has_subgroup_operations(kFlagScanSubgroupOperations) ? FlagHorizontalBins::scan
                                                                     : FlagHorizontalBins::indexed;
}

// layer_buffer = registers: its bins are registers either way, and a masked sample costs LAYERS
// compare-and-adds where an indexed one costs a load and a store per lane, so masked pays off to more
// layers than in the 3D buffer's pass. Alone on a 2-core AMD EPYC at 2.6 GHz, 800x600 hoops, k = 2, f16,
// one interleaved run, FLAG frame masked / indexed (median of the rounds' ratios [95%]): N = 13 0.616
// [0.609, 0.661]; 21 0.675; 25 0.711; 33 0.800; 41 0.851 [0.837, 0.876]; 57 0.979 [0.977, 1.121]; 81
// 1.109; 105 1.191; 153 1.517. Auto: masked up to 24 layers (N = 47), indexed beyond (the scan's
// intervals are the 3D buffer's: registers runs scan as indexed).
constexpr int kRegistersMaskedLastLayers = 24;

bool flag_registers_masked(FlagHorizontalBins bins, int layers) {
  return bins == FlagHorizontalBins::masked ||
         (bins == FlagHorizontalBins::automatic && layers <= kRegistersMaskedLastLayers);
}

std::uint32_t flag_horizontal_invocations_x(FlagHorizontalBins bins, int width_px, int spacing_px, int layers,
                                            int block) {
  const auto w = static_cast<std::uint32_t>(width_px), k = static_cast<std::uint32_t>(spacing_px);
  if (bins != FlagHorizontalBins::scan) return ceil_div(w, static_cast<std::uint32_t>(block) * k) * k;
  const std::uint32_t segments = ceil_div(ceil_div(w, k), static_cast<std::uint32_t>(kFlagScanSegment));
  return segments * k * ceil_div(static_cast<std::uint32_t>(layers), 8u) * 8u;
}

const std::vector<std::string>& flag_layer_buffers() {
  static const std::vector<std::string> buffers = {"auto", "full", "streamed", "registers"};
  return buffers;
}

std::string flag_registers_unsupported(const FilterOptions& options) {
  std::string why;
  if (options.buffer_scale != 1)
    why = fmt::format("buffer scale {} (the buffer it reduces is not there)", options.buffer_scale);
  else if (options.precision != "f32" && options.precision != "f16")
    why = fmt::format("{} layers", options.precision);
  else if (adaptive_on(options))
    why = "adaptive = on";
  if (why.empty()) return {};
  return fmt::format("flag: layer_buffer = registers runs buffer scale 1 with f32 or f16 layers and adaptive off, "
                     "not {}; layer_buffer auto or full runs it",
                     why);
}

FlagLayerBuffer flag_layer_buffering(const FilterOptions& options, const vk::DeviceInfo* device) {
  const auto chosen = options.choice<FlagLayerBuffer>("layer_buffer");
  if (chosen != FlagLayerBuffer::automatic) return chosen;
  // Every aperture: polygons too, measured faster than their buffer and its scan at N = 9-153, halved or
  // both halves, f16 and f32 (results/README.md, "polygons in registers by default").
  const bool runs_registers = device && device->is_software() &&
                              device->has_subgroup_operations(kFlagScanSubgroupOperations) &&
                              flag_registers_unsupported(options).empty();
  return runs_registers ? FlagLayerBuffer::registers : FlagLayerBuffer::full;
}

bool flag_runs_registers(const FilterOptions& options, const vk::DeviceInfo& device) {
  if (flag_layer_buffering(options, &device) != FlagLayerBuffer::registers) return false;
  if (const std::string why = flag_registers_unsupported(options); !why.empty()) throw std::invalid_argument(why);
  return true;
}

bool flag_fused_reads_tile_map(int layers, bool shape) { return layers >= (shape ? 15 : 13); }

std::uint32_t flag_fused_invocations_x(int width_px, int spacing_px) {
  const auto k = static_cast<std::uint32_t>(spacing_px);
  return ceil_div(ceil_div(static_cast<std::uint32_t>(width_px), k), 8u) * 8u * k;
}

// Auto band height: the ring within a byte budget per device kind, never under a floor of rows.
// lavapipe runs each dispatch to completion across its threads, so every band costs two pipeline
// launches and two thread-pool barriers: it wants few, tall bands; 16 MiB is the goal at
// 1080p / 41x41 f16 (B = 12 rows, 90 bands). A GPU wants the ring to stay in its L2 cache (tens of
// MiB) while a band still fills the device: 32 MiB (B = 64 rows at 1080p / 41x41 f16), a choice not
// yet measured on a GPU. The floor keeps large patterns (4K / 81x81 f16: a 1.3 MB row, 2 n k = 80
// rows already over either budget) from a dispatch pair per row. `memory --band-rows` lists the
// rings, `buffers --band-rows` times them interleaved (results/README.md, "Streamed FLAG layers").
constexpr std::uint64_t kFlagStreamBudgetSoftware = 16ull << 20, kFlagStreamBudgetGpu = 32ull << 20;
constexpr int kFlagStreamMinBand = 8;

int flag_stream_band_rows(int requested, bool software_device, int reach_rows, std::uint64_t row_bytes) {
  if (requested > 0) return requested;
  const std::uint64_t budget = software_device ? kFlagStreamBudgetSoftware : kFlagStreamBudgetGpu;
  const auto rows = static_cast<std::int64_t>(budget / std::max<std::uint64_t>(row_bytes, 1));
  return static_cast<int>(std::clamp<std::int64_t>(rows - 2 * reach_rows, kFlagStreamMinBand, 1 << 16));
}

int flag_stream_ring_rows(int band_rows, int reach_rows, int height) {
  return static_cast<int>(std::min<std::int64_t>(height, static_cast<std::int64_t>(band_rows) + 2 * reach_rows));
}

FlagStreamRing flag_stream_ring(const FlagBufferExtent& full, int spacing_px, LayerPrecision precision,
                                int requested_band_rows, bool software_device) {
  const int reach_rows = (full.layers - 1) * spacing_px;  // the rows a vertical pass reads away
  const std::uint64_t row_bytes =
      static_cast<std::uint64_t>(full.width) * full.layers * static_cast<std::uint64_t>(bytes_per_texel(precision));
  FlagStreamRing ring{flag_stream_band_rows(requested_band_rows, software_device, reach_rows, row_bytes), full};
  ring.extent.height = flag_stream_ring_rows(ring.band_rows, reach_rows, full.height);
  return ring;
}

void check_software_bounds(const vk::DeviceInfo& device, int block, int layers, bool bracketed) {
  if (!device.is_software()) return;
  if (block * layers > kSoftwareMaxBlockLayers)
    throw std::invalid_argument(fmt::format(
        "FLAG on {}: horizontal block {} x {} layers = {} bins per invocation, over the {} this driver computes "
        "correctly (beyond, it returns zero layers without an error); use --horizontal-block auto or a smaller N",
        device.name, block, layers, block * layers, kSoftwareMaxBlockLayers));
  if (bracketed && layers > kSoftwareMaxBracketedLayers)
    throw std::invalid_argument(fmt::format(
        "FLAG bracketed precisions on {}: {} layers, over the {} this driver computes correctly (beyond, the "
        "bracket pass returns NaN without an error); use f16, f32 or r11g11b10f, a buffer scale, or N <= {}",
        device.name, layers, kSoftwareMaxBracketedLayers, 2 * kSoftwareMaxBracketedLayers - 1));
}

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kImage = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
constexpr std::int32_t kBracketChunk = 32;  // pixels per invocation of flag_bracket.comp

}  // namespace

void check_frame_colour(GpuFrame& frame, LayerPrecision precision) {
  if (!is_unsigned(precision)) return;
  Image rgba(frame.params.width_px, frame.params.height_px, 4);
  vk::download(frame.ctx, frame.color, rgba.pixels.data(), rgba.pixels.size() * sizeof(float));
  check_layer_input(rgba, precision);
}

namespace {

class Flag final : public gpu::GpuFilter {
 public:
  Flag(GpuFrame& frame, const FlagConfig& config, bool registers)
      : frame_(frame),
        scale_(config.buffer_scale),
        pattern_(reduced_pattern(config.pattern, config.buffer_scale)),
        low_width_(ceil_div(frame.width(), scale_)),
        low_height_(ceil_div(frame.height(), scale_)),
        outputs_(flag_horizontal_block(config.horizontal_block, frame.ctx.info(), pattern_.layers())),
        bins_(flag_horizontal_binning(config.horizontal_bins, frame.ctx.info(), pattern_.layers())),
        tile_px_(config.adaptive ? config.adaptive_tile_px : 0),
        streamed_(config.streamed),
        layer_count_(pattern_.layers()) {
    check_frame_colour(frame, config.precision);
    if (registers) {  // both passes in one, at full resolution (flag_registers_unsupported)
      // By constant_id: 0 LAYERS, 2 SPACING, 5 MASKED_BINS, 6 TILE_PX, 7 TILE_MAP. A workgroup is 8
      // columns (fused.comp); the tile map's M bounds the samples it loads (bound where it is not read).
      tiles_.emplace(frame.ctx, frame.packed, low_width_, low_height_, pattern_.spacing_px, kFlagFusedTilePx);
      fused_.emplace(frame.ctx, vk::spirv(std::string("flag/fused_") + to_string(config.precision)),
                     std::vector<VkDescriptorType>{kBuffer, kBuffer, kBuffer}, sizeof(PassParams),
                     std::vector<std::int32_t>{layer_count_, 0, pattern_.spacing_px, 0, 0,
                                               flag_registers_masked(config.horizontal_bins, layer_count_),
                                               kFlagFusedTilePx, flag_fused_reads_tile_map(layer_count_)},
                     vk::LocalSize{8, 1});
      fused_->bind(0, frame.packed);
      fused_->bind(1, frame.output);
      fused_->bind(2, tiles_->buffer());
      return;
    }
    const vk::Buffer* flag_input = &frame.packed;
    const vk::Buffer* flag_output = &frame.output;
    if (scale_ > 1) {
      const VkDeviceSize low_bytes = static_cast<VkDeviceSize>(low_width_) * low_height_ * 16;
      packed_low_.emplace(vk::make_storage_buffer(frame.ctx, low_bytes, "low-res packed input"));
      output_low_.emplace(vk::make_storage_buffer(frame.ctx, low_bytes, "low-res FLAG output"));
      disc_area_low_.emplace(gpu::make_disc_area_buffer(frame.ctx, pattern_));
      downsample_.emplace(frame.ctx, vk::spirv("flag/downsample"),
                          std::vector<VkDescriptorType>{kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(PassParams),
                          std::vector<std::int32_t>{scale_, frame.params.width_px, frame.params.height_px,
                                                    pattern_.spacing_px});
      downsample_->bind(0, frame.color);
      downsample_->bind(1, frame.packed);
      downsample_->bind(2, *packed_low_);
      downsample_->bind(3, *disc_area_low_);
      upsample_.emplace(frame.ctx, vk::spirv("flag/upsample"),
                        std::vector<VkDescriptorType>{kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(PassParams),
                        std::vector<std::int32_t>{scale_, static_cast<std::int32_t>(low_width_),
                                                  static_cast<std::int32_t>(low_height_)});
      upsample_->bind(0, frame.color);
      upsample_->bind(1, frame.packed);
      upsample_->bind(2, *output_low_);
      upsample_->bind(3, frame.output);
      flag_input = &*packed_low_;
      flag_output = &*output_low_;
    }
    const bool bracketed = is_bracketed(config.precision);
    std::uint32_t extent_x = low_width_, extent_y = low_height_;
    if (tile_px_ > 0) {
      tiles_.emplace(frame.ctx, *flag_input, low_width_, low_height_, pattern_.spacing_px, tile_px_);
      // The scene's largest disc on FLAG's grid, reduced on the GPU when the run is prepared (CoC,
      // downsample and tile passes once, outside the timed frames); one int comes back. It sizes the
      // layers: n' = min(isqrt(m), n). A scene with no blur at all stores no layer: every tile passes
      // its input through, so the image is a placeholder of one texel.
      frame.ctx.submit_and_wait([&](VkCommandBuffer cmd) {
        frame.coc_pass.dispatch(cmd, &frame.params, frame.width(), frame.height());
        const PassParams grid = grid_params(frame.params);
        if (downsample_) downsample_->dispatch(cmd, &grid, low_width_, low_height_);
        tiles_->record(cmd, nullptr, grid);
      });
      scene_max_index_ = tiles_->read_scene_max_index();
      layer_count_ = scene_sized_pattern(pattern_, scene_max_index_).layers();
      if (scene_max_index_ == 0) extent_x = extent_y = 1;
      tile_layers_.emplace(frame.ctx, vk::spirv("flag/tile_layers"), std::vector<VkDescriptorType>{kBuffer},
                           sizeof(PassParams), std::vector<std::int32_t>{pattern_.spacing_px, tile_px_});
      tile_layers_->bind(0, tiles_->buffer());
    }
    // The scan runs no block (its difference array is kFlagScanSegment vec3 whatever the layers).
    check_software_bounds(frame.ctx.info(), bins_ == FlagHorizontalBins::scan ? 1 : outputs_, layer_count_, bracketed);
    const std::string variant = std::string(tile_px_ > 0 ? "_adaptive_" : "_") + to_string(config.precision);
    const bool scan = bins_ == FlagHorizontalBins::scan;
    // constant_id 4 is the tile size (adaptive; unused otherwise), 5 MASKED_BINS, 6 the scan's SEGMENT.
    std::vector<std::int32_t> horizontal_constants = {layer_count_, kBracketChunk, pattern_.spacing_px,
                                                      outputs_,     tile_px_,      bins_ == FlagHorizontalBins::masked,
                                                      kFlagScanSegment};
    // By constant_id: 0 LAYERS, 1 the tile size, 7 LAYER_ROWS (0: the full buffer), 8 BOTH_HALVES (false:
    // the disc), 9 COLUMN_ORDER (vertical_order); 2-6 are not the vertical pass's.
    std::vector<std::int32_t> vertical_constants(10, 0);
    vertical_constants[0] = layer_count_;
    vertical_constants[1] = tile_px_;
    vertical_constants[9] = flag_vertical_ordering(config.vertical_order, frame.ctx.info()) == FlagVerticalOrder::columns;
    // Streamed: the ring's rows (constant_id 7, LAYER_ROWS in shaders/flag/layer_rows.glsl; 0: full).
    if (config.streamed && extent_y > 1) {
      const FlagStreamRing ring = flag_stream_ring(
          {static_cast<int>(extent_x), static_cast<int>(extent_y), layer_count_}, pattern_.spacing_px,
          config.precision, config.band_rows, frame.ctx.info().is_software());
      band_rows_ = ring.band_rows;
      extent_y = static_cast<std::uint32_t>(ring.extent.height);
      horizontal_constants.push_back(static_cast<std::int32_t>(extent_y));
      vertical_constants[7] = static_cast<std::int32_t>(extent_y);
    }
    std::vector<VkDescriptorType> horizontal_bindings = {kBuffer, kImage}, vertical_bindings = {kImage, kBuffer};
    if (bracketed) horizontal_bindings.push_back(kBuffer), vertical_bindings.push_back(kBuffer);
    if (tile_px_ > 0) {
      horizontal_bindings.push_back(kBuffer);                 // the tile map
      vertical_bindings.insert(vertical_bindings.end(), {kBuffer, kBuffer});  // the tile map, FLAG's input
    }
    layers_.emplace(frame.ctx, layer_format(config.precision), extent_x, extent_y, static_cast<std::uint32_t>(layer_count_));
    // Scan: a workgroup is 8 layers of one row segment (lavapipe's 8 lanes, so its loads are uniform).
    horizontal_.emplace(frame.ctx, vk::spirv(std::string(scan ? "flag/horizontal_scan" : "flag/horizontal") + variant),
                        horizontal_bindings, sizeof(PassParams), horizontal_constants,
                        scan ? vk::LocalSize{8, 1} : vk::LocalSize{});
    vertical_.emplace(frame.ctx, vk::spirv("flag/vertical" + variant), vertical_bindings, sizeof(PassParams),
                      vertical_constants);
    horizontal_->bind(0, *flag_input);
    horizontal_->bind(1, *layers_);
    vertical_->bind(0, *layers_);
    vertical_->bind(1, *flag_output);
    const std::uint32_t after_brackets = bracketed ? 3 : 2;
    if (tile_px_ > 0) {
      horizontal_->bind(after_brackets, tiles_->buffer());
      vertical_->bind(after_brackets, tiles_->buffer());
      vertical_->bind(after_brackets + 1, *flag_input);
    }
    if (bracketed) {
      brackets_.emplace(vk::make_storage_buffer(
          frame.ctx, flag_bracket_buffer_bytes(low_height_, static_cast<std::uint32_t>(layer_count_)),
          "FLAG bracket buffer"));
      std::vector<std::int32_t> constants = {layer_count_, kBracketChunk, pattern_.spacing_px};
      std::vector<VkDescriptorType> bindings = {kBuffer, kBuffer, kBuffer};
      if (tile_px_ > 0) constants.insert(constants.end(), {1, tile_px_}), bindings.push_back(kBuffer);
      bracket_.emplace(frame.ctx, vk::spirv(tile_px_ > 0 ? "flag/bracket_adaptive" : "flag/bracket"), bindings,
                       sizeof(PassParams), constants);
      bracket_->bind(0, *flag_input);
      bracket_->bind(2, *brackets_);
      if (tile_px_ > 0) bracket_->bind(3, tiles_->buffer());
      horizontal_->bind(2, *brackets_);
      vertical_->bind(2, *brackets_);
    }
  }

  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    // frame_.params may be a warm-up's smaller region: derive the low-res one from it each time.
    const PassParams full = frame_.params;
    const PassParams grid = grid_params(full);
    PassParams low = grid;
    low.half_n = layer_count_ - 1;  // the layers allocated (adaptive: what the scene needs)
    const auto lw = static_cast<std::uint32_t>(low.width_px), lh = static_cast<std::uint32_t>(low.height_px);
    if (fused_) {
      if (flag_fused_reads_tile_map(layer_count_)) tiles_->record_max(cmd, &timer, grid);
      // Workgroups (column block + blocks x column phase, row phase): one per 8 columns of a phase.
      fused_->dispatch(cmd, &low, flag_fused_invocations_x(low.width_px, pattern_.spacing_px),
                       static_cast<std::uint32_t>(pattern_.spacing_px));
      timer.end_pass(cmd, "fused");
      return;
    }
    if (downsample_) {
      downsample_->dispatch(cmd, &grid, lw, lh);
      timer.end_pass(cmd, "downsample");
    }
    if (tiles_) {
      tiles_->record(cmd, &timer, grid);
      const auto t = static_cast<std::uint32_t>(tile_px_);
      tile_layers_->dispatch(cmd, &low, ceil_div(lw, t), ceil_div(lh, t));
      timer.end_pass(cmd, "tile_layers");
    }
    if (bracket_) {
      const VkDeviceSize half = brackets_->bytes() / 2;
      vkCmdFillBuffer(cmd, brackets_->get(), 0, half, 0xffffffffu);  // min: above every float's bits
      vkCmdFillBuffer(cmd, brackets_->get(), half, half, 0u);         // max
      VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
      barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
      barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
      vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier,
                           0, nullptr, 0, nullptr);
      bracket_->dispatch(cmd, &low, ceil_div(lw, kBracketChunk), lh);
      timer.end_pass(cmd, "bracket");
    }
    if (band_rows_ > 0) {
      // Streamed: per band, the horizontal pass fills the ring up to the band's last row + n k (the
      // rows not yet written), then the vertical pass sums the band; dispatch() ends each with a
      // barrier, so a band's rows are written before they are read and read before the ring wraps
      // onto them. One timestamp for the whole: per-band stamps would outnumber the query pool.
      const int reach_rows = (layer_count_ - 1) * pattern_.spacing_px, h = low.height_px;
      int written = 0;  // rows of layers written so far
      for (int y0 = 0; y0 < h; y0 += band_rows_) {
        const int y1 = std::min(h, y0 + band_rows_), needed = std::min(h, y1 + reach_rows);
        if (needed > written) record_horizontal(cmd, low, written, needed);
        written = std::max(written, needed);
        PassParams band = low;
        band.band_y0_px = y0, band.band_y1_px = y1;
        vertical_->dispatch(cmd, &band, lw, static_cast<std::uint32_t>(y1 - y0));
      }
      timer.end_pass(cmd, "streamed");
    } else {
      // Streamed without a ring (adaptive, a scene with no blur: no layer at all) stamps as streamed.
      record_horizontal(cmd, low, 0, low.height_px);
      if (!streamed_) timer.end_pass(cmd, "horizontal");
      low.band_y0_px = 0, low.band_y1_px = low.height_px;
      vertical_->dispatch(cmd, &low, lw, lh);
      timer.end_pass(cmd, streamed_ ? "streamed" : "vertical");
    }
    if (upsample_) {
      upsample_->dispatch(cmd, &full, frame_.width(), frame_.height());
      timer.end_pass(cmd, "upsample");
    }
  }

  std::uint64_t intermediate_bytes() const override {
    std::uint64_t bytes = layers_ ? layers_->allocated_bytes() : 0;
    for (const auto* b : {&packed_low_, &output_low_, &brackets_, &disc_area_low_})
      if (*b) bytes += (*b)->allocated_bytes();
    if (tiles_) bytes += tiles_->allocated_bytes();
    return bytes;
  }

  // Adaptive: what the tile map found in the last frame and the layers allocated.
  nlohmann::json stats() override {
    if (tile_px_ == 0) return nlohmann::json::object();  // the fused pass's map has M alone
    const PassParams grid = grid_params(frame_.params);
    nlohmann::json out = coc_tiles_stats(tiles_->read(grid.width_px, grid.height_px), pattern_, grid.width_px,
                                         grid.height_px);
    out["layers"] = layer_count_;
    out["layers_worst_case"] = pattern_.layers();
    out["scene_max_disc_index_when_prepared"] = scene_max_index_;
    return {{"adaptive", out}};
  }

 private:
  // The horizontal pass over rows [y0, y1) of FLAG's grid (`low`: its parameters).
  void record_horizontal(VkCommandBuffer cmd, const PassParams& low, int y0, int y1) const {
    PassParams band = low;
    band.band_y0_px = y0, band.band_y1_px = y1;
    horizontal_->dispatch(cmd, &band,
                          flag_horizontal_invocations_x(bins_, low.width_px, pattern_.spacing_px, layer_count_, outputs_),
                          static_cast<std::uint32_t>(y1 - y0));
  }

  // FLAG's grid (full or reduced resolution) for the frame region `full`, with its pattern's n.
  PassParams grid_params(const PassParams& full) const {
    PassParams low = full;
    low.width_px = ceil_div(full.width_px, scale_);
    low.height_px = ceil_div(full.height_px, scale_);
    low.half_n = pattern_.half();
    low.max_radius_px = pattern_.max_radius_px();
    return low;
  }

  GpuFrame& frame_;
  std::int32_t scale_;
  GatherPattern pattern_;  // the (low-res) pattern the FLAG passes run
  std::uint32_t low_width_, low_height_;
  std::int32_t outputs_;   // pixels per invocation of the horizontal pass
  FlagHorizontalBins bins_;  // the horizontal pass's binning as run (never automatic)
  std::int32_t tile_px_;   // adaptive: the tile map's tile size; 0: worst case
  bool streamed_;          // layer_buffer = streamed
  std::int32_t layer_count_;  // allocated: the pattern's ceil(N/2), or (adaptive) what the scene needs
  int scene_max_index_ = -1;  // adaptive: the scene's largest disc index when prepared
  int band_rows_ = 0;  // streamed: output rows per band; 0: the full buffer
  std::optional<gpu::CocTilesGpu> tiles_;
  std::optional<vk::StorageImage3D> layers_;
  std::optional<vk::ComputePipeline> horizontal_, vertical_, tile_layers_;
  std::optional<vk::ComputePipeline> fused_;  // layer_buffer = registers: both passes, no layers_
  std::optional<vk::Buffer> packed_low_, output_low_, brackets_, disc_area_low_;
  std::optional<vk::ComputePipeline> downsample_, upsample_, bracket_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_flag_gpu(GpuFrame& frame, const FilterOptions& options) {
  if (!options.aperture.is_disc()) throw std::logic_error("make_flag_gpu: the disc only (make_flag_shape_gpu: others)");
  return std::make_unique<Flag>(frame, flag_config(options), flag_runs_registers(options, frame.ctx.info()));
}

}  // namespace bokeh
