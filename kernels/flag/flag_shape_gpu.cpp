// GPU FLAG for any convex aperture (flag_shape.hpp): shape_pack (colour / area and the area, per
// pixel), horizontal_shape (chord extents into a 3D image of (N + 1) / 2 or N layers; scan bins:
// horizontal_shape_scan, interval sums by row sections), vertical.
// layer_buffer = streamed (flag_gpu.hpp): the layers in a ring of B + 2 n k rows, the two passes
// alternating per band, as the disc's FLAG does (the full buffer's image bit for bit). f32 / f16 /
// r11g11b10f, indexed, masked or scan bins, scale 1, adaptive off (flag_method.cpp's aperture_unsupported
// refuses the others before this is made).
#include <algorithm>
#include <optional>
#include <string>
#include <stdexcept>

#include "coc_tiles_gpu.hpp"
#include "flag_config.hpp"
#include "flag_gpu.hpp"
#include "flag_shape.hpp"
#include "flag_shape_gpu.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kImage = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;

}  // namespace

// Auto for a non-disc aperture. GPUs: indexed, as for the disc. Software devices (lavapipe) with the
// scan's subgroup operations: scan from 7 layers on, whether the shape is halved or not; never masked
// (2.5-9x indexed's time: its per-layer selects do not pay for a chord load). Once the scan's lanes hand
// samples on by shuffle it beat the indexed bins wherever they had kept pace before (both halves up to
// 81 layers; halved under 12). `bokehbench ab`, auto built as today against auto built as scan, alone on
// a 2-core AMD EPYC at 2.6 GHz, lavapipe, 800x600 hoops, k = 2, f16, FLAG frame in process CPU time,
// scan / indexed [95%] (results/scan_shuffle/ab_auto_blades*.json):
// - blades6 (halved, (N + 1) / 2 layers): N = 5 1.233 [1.204, 1.250]; 9 1.049 [0.950, 1.073]; 13 0.910
//   [0.894, 0.948]; 21 0.897 [0.878, 0.919] (N = 17: scan already).
// - blades5 (both halves, N layers): N = 9 0.976 [0.927, 1.002]; 21 0.930 [0.892, 0.973]; 41 0.920
//   [0.911, 0.929]; 61 0.849 [0.782, 0.873]; 81 0.837 [0.773, 0.866].
constexpr int kSoftwareShapeScanFirstLayers = 7;

FlagHorizontalBins flag_shape_binning(FlagHorizontalBins bins, const vk::DeviceInfo& device, int layers) {
  if (bins != FlagHorizontalBins::automatic) return bins;
  if (!device.is_software()) return FlagHorizontalBins::indexed;
  const bool scan =
      layers >= kSoftwareShapeScanFirstLayers && device.has_subgroup_operations(kFlagScanSubgroupOperations);
  return scan ? FlagHorizontalBins::scan : FlagHorizontalBins::indexed;
}

namespace {

class FlagShape final : public gpu::GpuFilter {
 public:
  FlagShape(gpu::GpuFrame& frame, const FlagConfig& config, const Aperture& aperture, bool registers)
      : frame_(frame),
        table_(aperture, config.pattern),
        // registers bins by chords, masked or indexed as for the disc (scan's row sections are the 3D
        // buffer's). blades6 in registers, masked / indexed: 0.74 at N = 9, 0.85 at 21, 0.985 at 41.
        bins_(!registers ? flag_shape_binning(config.horizontal_bins, frame.ctx.info(), table_.layers())
              : flag_registers_masked(config.horizontal_bins, table_.layers()) ? FlagHorizontalBins::masked
                                                                                : FlagHorizontalBins::indexed),
        outputs_(scan() ? 1 : flag_horizontal_block(config.horizontal_block, frame.ctx.info(), table_.layers())),
        sorted_(vk::make_storage_buffer(frame.ctx, table_.lattice.sorted.size() * sizeof(float), "sorted aperture gauges")),
        // The scan reads the row sections, the other binnings the chords: only that one is on the device.
        table_buffer_(vk::make_storage_buffer(frame.ctx, table_.bytes(scan()),
                                              scan() ? "FLAG row-section table" : "FLAG chord table")),
        weighted_(vk::make_storage_buffer(frame.ctx, static_cast<VkDeviceSize>(frame.width()) * frame.height() * 16,
                                          "FLAG shape-weighted colour")),
        rows_(flag_shape_layer_rows(config, table_.layers(), frame.width(), frame.height(),
                                    frame.ctx.info().is_software())),
        streamed_(config.streamed),
        pack_(frame.ctx, vk::spirv("flag/shape_pack"), std::vector<VkDescriptorType>(4, kBuffer),
              sizeof(gpu::PassParams)) {
    const std::string precision = to_string(config.precision);
    if (registers) {
      // layer_buffer = registers (shaders/flag/fused.comp with SHAPE): constant ids 0 LAYERS, 2 SPACING,
      // 5 MASKED_BINS, 6 TILE_PX, 7 TILE_MAP, 8 BOTH_HALVES; a workgroup is 8 columns of a lattice
      // phase. The tile map holds shape_pack's areas (flag_fused_reads_tile_map: from 15 layers on).
      tiles_.emplace(frame.ctx, weighted_, frame.width(), frame.height(), config.pattern.spacing_px,
                     kFlagFusedTilePx, true);
      fused_.emplace(frame.ctx, vk::spirv("flag/fused_shape_" + precision),
                     std::vector<VkDescriptorType>{kBuffer, kBuffer, kBuffer, kBuffer}, sizeof(gpu::PassParams),
                     std::vector<std::int32_t>{table_.layers(), 0, config.pattern.spacing_px, 0, 0,
                                               bins_ == FlagHorizontalBins::masked, kFlagFusedTilePx,
                                               reads_tile_map(), !table_.halved},
                     vk::LocalSize{8, 1});
    } else {
      layers_.emplace(frame.ctx, layer_format(config.precision), static_cast<std::uint32_t>(frame.width()),
                      static_cast<std::uint32_t>(rows_.extent.height), static_cast<std::uint32_t>(table_.layers()));
      // constant ids: 0 LAYERS, 2 SPACING, 3 OUTPUTS, 5 MASKED_BINS, 6 the scan's SEGMENT, 7 LAYER_ROWS
      // (0: the full buffer), 8 BOTH_HALVES. Scan: a workgroup is 8 layers of one row segment
      // (lavapipe's 8 SIMD lanes), as the disc's scan.
      horizontal_.emplace(frame.ctx,
                          vk::spirv(std::string(scan() ? "flag/horizontal_shape_scan_" : "flag/horizontal_shape_") +
                                    precision),
                          std::vector<VkDescriptorType>{kBuffer, kImage, kBuffer}, sizeof(gpu::PassParams),
                          std::vector<std::int32_t>{table_.layers(), 0, config.pattern.spacing_px, outputs_, 0,
                                                    bins_ == FlagHorizontalBins::masked, kFlagScanSegment,
                                                    layer_ring_rows(), !table_.halved},
                          scan() ? vk::LocalSize{8, 1} : vk::LocalSize{});
      vertical_.emplace(frame.ctx, vk::spirv("flag/vertical_" + precision),
                        std::vector<VkDescriptorType>{kImage, kBuffer}, sizeof(gpu::PassParams),
                        std::vector<std::int32_t>{table_.layers(), 0, 0, 0, 0, 0, 0, layer_ring_rows(),
                                                  !table_.halved,
                                                  flag_vertical_ordering(config.vertical_order, frame.ctx.info()) ==
                                                      FlagVerticalOrder::columns});
    }
    if (is_bracketed(config.precision) || config.buffer_scale != 1 || config.adaptive)
      throw std::logic_error("make_flag_shape_gpu: a configuration aperture_unsupported refuses");
    check_frame_colour(frame, config.precision);
    // The scan runs no block (its difference array is kFlagScanSegment vec3 whatever the layers).
    check_software_bounds(frame.ctx.info(), outputs_, table_.layers(), false);
    vk::upload(frame.ctx, sorted_, table_.lattice.sorted.data(), table_.lattice.sorted.size() * sizeof(float));
    if (scan())
      vk::upload(frame.ctx, table_buffer_, table_.sections.data(), table_.section_bytes());
    else
      vk::upload(frame.ctx, table_buffer_, table_.chords.data(), table_.chord_bytes());
    pack_.bind(0, frame.packed);
    pack_.bind(1, frame.color);
    pack_.bind(2, sorted_);
    pack_.bind(3, weighted_);
    if (fused_) {
      fused_->bind(0, weighted_);
      fused_->bind(1, frame.output);
      fused_->bind(2, table_buffer_);
      fused_->bind(3, tiles_->buffer());
      return;
    }
    horizontal_->bind(0, weighted_);
    horizontal_->bind(1, *layers_);
    horizontal_->bind(2, table_buffer_);
    vertical_->bind(0, *layers_);
    vertical_->bind(1, frame.output);
  }

  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    gpu::PassParams params = frame_.params;  // a warm-up's region or the frame's
    params.band_y0_px = 0, params.band_y1_px = params.height_px;
    const auto w = static_cast<std::uint32_t>(params.width_px), h = static_cast<std::uint32_t>(params.height_px);
    pack_.dispatch(cmd, &params, w, h);
    timer.end_pass(cmd, "shape_pack");
    if (fused_) {  // as the disc's (flag_gpu.cpp): one workgroup per 8 columns of a phase
      if (reads_tile_map()) tiles_->record_max(cmd, &timer, params);
      fused_->dispatch(cmd, &params, flag_fused_invocations_x(params.width_px, params.spacing_px),
                       static_cast<std::uint32_t>(params.spacing_px));
      timer.end_pass(cmd, "fused");
      return;
    }
    const std::uint32_t horizontal_x =
        flag_horizontal_invocations_x(bins_, params.width_px, params.spacing_px, table_.layers(), outputs_);
    if (!streamed_) {
      horizontal_->dispatch(cmd, &params, horizontal_x, h);
      timer.end_pass(cmd, "horizontal");
      vertical_->dispatch(cmd, &params, w, h);
      timer.end_pass(cmd, "vertical");
      return;
    }
    // Streamed, as the disc's FLAG (flag_gpu.cpp): per band, the horizontal pass fills the ring up to
    // the band's last row + n k, then the vertical pass sums the band; dispatch() ends each with a
    // barrier. One timestamp for the whole.
    const int reach_rows = params.half_n * params.spacing_px, height = params.height_px;
    int written = 0;  // rows of layers written so far
    for (int y0 = 0; y0 < height; y0 += rows_.band_rows) {
      const int y1 = std::min(height, y0 + rows_.band_rows), needed = std::min(height, y1 + reach_rows);
      gpu::PassParams band = params;
      if (needed > written) {
        band.band_y0_px = written, band.band_y1_px = needed;
        horizontal_->dispatch(cmd, &band, horizontal_x, static_cast<std::uint32_t>(needed - written));
        written = needed;
      }
      band.band_y0_px = y0, band.band_y1_px = y1;
      vertical_->dispatch(cmd, &band, w, static_cast<std::uint32_t>(y1 - y0));
    }
    timer.end_pass(cmd, "streamed");
  }

  std::uint64_t intermediate_bytes() const override {
    return (layers_ ? layers_->allocated_bytes() : 0) + weighted_.allocated_bytes() + sorted_.allocated_bytes() +
           table_buffer_.allocated_bytes() + (tiles_ ? tiles_->allocated_bytes() : 0);
  }

 private:
  gpu::GpuFrame& frame_;
  FlagShapeTable table_;
  bool scan() const { return bins_ == FlagHorizontalBins::scan; }
  bool reads_tile_map() const { return flag_fused_reads_tile_map(table_.half_n + 1, true); }
  // LAYER_ROWS (shaders/flag/layer_rows.glsl): the ring's rows, or 0 for the full buffer.
  std::int32_t layer_ring_rows() const { return streamed_ ? rows_.extent.height : 0; }

  FlagHorizontalBins bins_;  // as run (never automatic)
  std::int32_t outputs_;     // pixels per invocation of the horizontal pass (scan: 1, unused)
  vk::Buffer sorted_, table_buffer_, weighted_;
  FlagStreamRing rows_;   // the layer image's extent (streamed: the ring's) and band (0: full)
  bool streamed_;
  vk::ComputePipeline pack_;
  std::optional<vk::StorageImage3D> layers_;                    // the 3D buffer's passes
  std::optional<vk::ComputePipeline> horizontal_, vertical_;
  std::optional<gpu::CocTilesGpu> tiles_;                       // the fused pass's map of areas
  std::optional<vk::ComputePipeline> fused_;                    // layer_buffer = registers
};

}  // namespace

FlagStreamRing flag_shape_layer_rows(const FlagConfig& c, int layers, int width_px, int height_px,
                                     bool software_device) {
  FlagStreamRing ring{0, {width_px, height_px, layers}};
  if (!c.streamed) return ring;
  // The vertical pass reads rows y - n k .. y + n k whatever the layers hold (both halves or one).
  const int reach_rows = c.pattern.half() * c.pattern.spacing_px;
  const std::uint64_t row_bytes = static_cast<std::uint64_t>(width_px) * layers * bytes_per_texel(c.precision);
  ring.band_rows = flag_stream_band_rows(c.band_rows, software_device, reach_rows, row_bytes);
  ring.extent.height = flag_stream_ring_rows(ring.band_rows, reach_rows, height_px);
  return ring;
}

std::unique_ptr<gpu::GpuFilter> make_flag_shape_gpu(gpu::GpuFrame& frame, const FilterOptions& options) {
  return std::make_unique<FlagShape>(frame, flag_config(options), options.aperture,
                                     flag_runs_registers(options, frame.ctx.info()));
}

}  // namespace bokeh
