// GPU FLAG for any convex aperture (flag_shape.hpp): shape_pack (colour / area and the area, per
// pixel), horizontal_shape (chord extents into a 3D image of (N + 1) / 2 or N layers), vertical.
// The main path only: the full layer buffer, f32 / f16 / r11g11b10f, indexed bins, scale 1, adaptive
// off (flag_method.cpp's aperture_unsupported refuses the others before this is made).
#include <stdexcept>

#include <fmt/format.h>

#include "ceil_div.hpp"
#include "flag_config.hpp"
#include "flag_gpu.hpp"
#include "flag_shape.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

namespace {

constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kImage = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;

class FlagShape final : public gpu::GpuFilter {
 public:
  FlagShape(gpu::GpuFrame& frame, const FlagConfig& config, const Aperture& aperture)
      : frame_(frame),
        table_(aperture, config.pattern),
        outputs_(flag_horizontal_block(config.horizontal_block, frame.ctx.info(), table_.layers())),
        sorted_(vk::make_storage_buffer(frame.ctx, table_.lattice.sorted.size() * sizeof(float), "sorted aperture gauges")),
        chords_(vk::make_storage_buffer(frame.ctx, table_.bytes(), "FLAG chord table")),
        weighted_(vk::make_storage_buffer(frame.ctx, static_cast<VkDeviceSize>(frame.width()) * frame.height() * 16,
                                          "FLAG shape-weighted colour")),
        layers_(frame.ctx, layer_format(config.precision), static_cast<std::uint32_t>(frame.width()),
                static_cast<std::uint32_t>(frame.height()), static_cast<std::uint32_t>(table_.layers())),
        pack_(frame.ctx, vk::spirv("flag/shape_pack"), std::vector<VkDescriptorType>(4, kBuffer),
              sizeof(gpu::PassParams)),
        // constant ids: 0 LAYERS, 2 SPACING, 3 OUTPUTS, 7 LAYER_ROWS (0: the full buffer), 8 BOTH_HALVES.
        horizontal_(frame.ctx, vk::spirv("flag/horizontal_shape_" + std::string(to_string(config.precision))),
                    std::vector<VkDescriptorType>{kBuffer, kImage, kBuffer}, sizeof(gpu::PassParams),
                    std::vector<std::int32_t>{table_.layers(), 0, config.pattern.spacing_px, outputs_, 0, 0, 0, 0,
                                              !table_.halved}),
        vertical_(frame.ctx, vk::spirv("flag/vertical_" + std::string(to_string(config.precision))),
                  std::vector<VkDescriptorType>{kImage, kBuffer}, sizeof(gpu::PassParams),
                  std::vector<std::int32_t>{table_.layers(), 0, 0, 0, 0, 0, 0, 0, !table_.halved}) {
    if (is_bracketed(config.precision) || config.buffer_scale != 1 || config.adaptive || config.streamed)
      throw std::logic_error("make_flag_shape_gpu: a configuration aperture_unsupported refuses");
    check_frame_colour(frame, config.precision);
    if (frame.ctx.info().is_software() && outputs_ * table_.layers() > kFlagSoftwareMaxBlockLayers)
      throw std::invalid_argument(fmt::format(
          "FLAG on {}: horizontal block {} x {} layers, over the {} bins this driver computes correctly; use "
          "--horizontal-block auto or a smaller N", frame.ctx.info().name, outputs_, table_.layers(),
          kFlagSoftwareMaxBlockLayers));
    vk::upload(frame.ctx, sorted_, table_.lattice.sorted.data(), table_.lattice.sorted.size() * sizeof(float));
    vk::upload(frame.ctx, chords_, table_.chords.data(), table_.bytes());
    pack_.bind(0, frame.packed);
    pack_.bind(1, frame.color);
    pack_.bind(2, sorted_);
    pack_.bind(3, weighted_);
    horizontal_.bind(0, weighted_);
    horizontal_.bind(1, layers_);
    horizontal_.bind(2, chords_);
    vertical_.bind(0, layers_);
    vertical_.bind(1, frame.output);
  }

  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    gpu::PassParams params = frame_.params;  // a warm-up's region or the frame's
    params.band_y0_px = 0, params.band_y1_px = params.height_px;
    const auto w = static_cast<std::uint32_t>(params.width_px), h = static_cast<std::uint32_t>(params.height_px);
    const auto k = static_cast<std::uint32_t>(params.spacing_px);
    pack_.dispatch(cmd, &params, w, h);
    timer.end_pass(cmd, "shape_pack");
    horizontal_.dispatch(cmd, &params, ceil_div(w, static_cast<std::uint32_t>(outputs_) * k) * k, h);
    timer.end_pass(cmd, "horizontal");
    vertical_.dispatch(cmd, &params, w, h);
    timer.end_pass(cmd, "vertical");
  }

  std::uint64_t intermediate_bytes() const override {
    return layers_.allocated_bytes() + weighted_.allocated_bytes() + sorted_.allocated_bytes() +
           chords_.allocated_bytes();
  }

 private:
  gpu::GpuFrame& frame_;
  FlagShapeTable table_;
  std::int32_t outputs_;  // pixels per invocation of the horizontal pass
  vk::Buffer sorted_, chords_, weighted_;
  vk::StorageImage3D layers_;
  vk::ComputePipeline pack_, horizontal_, vertical_;
};

}  // namespace

std::unique_ptr<gpu::GpuFilter> make_flag_shape_gpu(gpu::GpuFrame& frame, const FlagConfig& config,
                                                    const Aperture& aperture) {
  return std::make_unique<FlagShape>(frame, config, aperture);
}

}  // namespace bokeh
