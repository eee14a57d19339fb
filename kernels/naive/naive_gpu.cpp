// GPU naive quadratic gather: one pass over the packed input, OUTPUTS_X x OUTPUTS_Y outputs per
// invocation at stride k (shaders/naive/gather.comp).
#include "naive_gpu.hpp"

#include <optional>
#include <stdexcept>

#include "ceil_div.hpp"
#include "coc_tiles_gpu.hpp"
#include "naive_config.hpp"
#include "naive_shape.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

const std::vector<std::string>& naive_gather_blocks() {
  static const std::vector<std::string> blocks = {"auto", "1x1", "4x1", "4x4", "8x4", "8x8"};
  return blocks;
}

OptionSpec naive_gather_block_option() {
  return {"gather_block",
          "naive gather: outputs per GPU invocation, at stride k (auto: 8x4 on CPU devices such as lavapipe, 1x1 "
          "on GPUs; every block gives the same image)",
          0, 0, 0, false, naive_gather_blocks()};
}

GatherBlock naive_gather_block(std::optional<GatherBlock> requested, const vk::DeviceInfo& device) {
  if (requested) return *requested;
  return device.is_software() ? GatherBlock{8, 4} : GatherBlock{1, 1};
}

namespace {

class NaiveGather final : public gpu::GpuFilter {
 public:
  // tile_px > 0: adaptive (the tile-max CoC map bounds each workgroup's gather, shaders/naive/gather.comp).
  NaiveGather(gpu::GpuFrame& frame, GatherBlock block, int tile_px)
      : frame_(frame),
        block_(block),
        tiles_(tile_px > 0 ? std::optional<gpu::CocTilesGpu>(std::in_place, frame.ctx, frame.packed, frame.width(),
                                                              frame.height(), frame.params.spacing_px, tile_px)
                           : std::nullopt),
        gather_(frame.ctx, vk::spirv(tiles_ ? "naive/gather_adaptive" : "naive/gather"),
                tiles_ ? std::vector<VkDescriptorType>(3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER)
                       : std::vector<VkDescriptorType>(2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                sizeof(gpu::PassParams),
                tiles_ ? std::vector<std::int32_t>{block.x, block.y, tile_px} : std::vector<std::int32_t>{block.x, block.y}) {
    gather_.bind(0, frame.packed);
    gather_.bind(1, frame.output);
    if (tiles_) gather_.bind(2, tiles_->buffer());
  }
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    if (tiles_) tiles_->record(cmd, &timer, frame_.params);
    // Invocation (gx, gy) covers block (gx / k, gy / k) of x k by y k pixels, phase (gx % k, gy % k).
    const auto k = static_cast<std::uint32_t>(frame_.params.spacing_px);
    const auto bx = static_cast<std::uint32_t>(block_.x), by = static_cast<std::uint32_t>(block_.y);
    gather_.dispatch(cmd, &frame_.params, ceil_div(frame_.width(), bx * k) * k, ceil_div(frame_.height(), by * k) * k);
    timer.end_pass(cmd, "gather");
  }
  std::uint64_t intermediate_bytes() const override { return tiles_ ? tiles_->allocated_bytes() : 0; }
  nlohmann::json stats() override {
    if (!tiles_) return nlohmann::json::object();
    const GatherPattern pattern{2 * frame_.params.half_n + 1, frame_.params.spacing_px};
    return {{"adaptive", coc_tiles_stats(tiles_->read(frame_.params.width_px, frame_.params.height_px), pattern,
                                         frame_.params.width_px, frame_.params.height_px)}};
  }

 private:
  gpu::GpuFrame& frame_;
  GatherBlock block_;
  std::optional<gpu::CocTilesGpu> tiles_;
  vk::ComputePipeline gather_;
};

}  // namespace

NaiveShapeGather::NaiveShapeGather(gpu::GpuFrame& frame, const Aperture& aperture, int tile_px)
    : frame_(frame),
      lattice_(aperture, GatherPattern{2 * frame.params.half_n + 1, frame.params.spacing_px}),
      tiles_(tile_px > 0 ? std::optional<gpu::CocTilesGpu>(std::in_place, frame.ctx, frame.packed, frame.width(),
                                                            frame.height(), frame.params.spacing_px, tile_px)
                         : std::nullopt),
      gauge_(vk::make_storage_buffer(frame.ctx, lattice_.gauge.size() * sizeof(float), "aperture gauge table")),
      sorted_(vk::make_storage_buffer(frame.ctx, lattice_.sorted.size() * sizeof(float), "sorted aperture gauges")),
      weighted_(vk::make_storage_buffer(frame.ctx, static_cast<VkDeviceSize>(frame.width()) * frame.height() * 16,
                                        "shape-weighted colour")),
      pack_(frame.ctx, vk::spirv("naive/shape_pack"), std::vector<VkDescriptorType>(4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
            sizeof(gpu::PassParams)),
      gather_(frame.ctx, vk::spirv(tiles_ ? "naive/gather_shape_adaptive" : "naive/gather_shape"),
              std::vector<VkDescriptorType>(tiles_ ? 4 : 3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER), sizeof(gpu::PassParams),
              tiles_ ? std::vector<std::int32_t>{tile_px} : std::vector<std::int32_t>{}) {
  vk::upload(frame.ctx, gauge_, lattice_.gauge.data(), lattice_.gauge.size() * sizeof(float));
  vk::upload(frame.ctx, sorted_, lattice_.sorted.data(), lattice_.sorted.size() * sizeof(float));
  pack_.bind(0, frame.packed);
  pack_.bind(1, frame.color);
  pack_.bind(2, sorted_);
  pack_.bind(3, weighted_);
  gather_.bind(0, weighted_);
  gather_.bind(1, frame.output);
  gather_.bind(2, gauge_);
  if (tiles_) gather_.bind(3, tiles_->buffer());
}

void NaiveShapeGather::record_pack(VkCommandBuffer cmd, vk::TimestampQueries& timer) {
  if (tiles_) tiles_->record(cmd, &timer, frame_.params);
  pack_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
  timer.end_pass(cmd, "shape_pack");
}

void NaiveShapeGather::record_gather(VkCommandBuffer cmd, vk::TimestampQueries& timer) {
  gather_.dispatch(cmd, &frame_.params, frame_.width(), frame_.height());
  timer.end_pass(cmd, "gather");
}

std::uint64_t NaiveShapeGather::intermediate_bytes() const {
  return gauge_.allocated_bytes() + sorted_.allocated_bytes() + weighted_.allocated_bytes() +
         (tiles_ ? tiles_->allocated_bytes() : 0);
}

nlohmann::json NaiveShapeGather::stats() {
  if (!tiles_) return nlohmann::json::object();
  const GatherPattern pattern{2 * frame_.params.half_n + 1, frame_.params.spacing_px};
  return {{"adaptive", coc_tiles_stats(tiles_->read(frame_.params.width_px, frame_.params.height_px), pattern,
                                       frame_.params.width_px, frame_.params.height_px)}};
}

std::unique_ptr<gpu::GpuFilter> make_naive_gpu(gpu::GpuFrame& frame, const FilterOptions& options) {
  const NaiveConfig c = naive_config(options);
  if (!options.aperture.is_disc())
    return std::make_unique<NaiveShapeGather>(frame, options.aperture, c.adaptive ? c.adaptive_tile_px : 0);
  return std::make_unique<NaiveGather>(frame, naive_gather_block(c.gather_block, frame.ctx.info()),
                                       c.adaptive ? c.adaptive_tile_px : 0);
}

}  // namespace bokeh
