#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "coc_tiles_gpu.hpp"
#include "method.hpp"
#include "naive_shape.hpp"
#include "vk/compute_pipeline.hpp"
#include "vk/memory.hpp"

namespace bokeh {

// Outputs per invocation of the gather shader (OUTPUTS_X x OUTPUTS_Y in shaders/naive/gather.comp),
// the method's option "gather_block": "auto" picks 8x4 on CPU devices (lavapipe, where a buffer load
// costs a scalar load per lane and a block divides the loads by up to 32) and 1x1, the plain shader,
// on GPUs (not yet measured there with blocks: see the option's help).
const std::vector<std::string>& naive_gather_blocks();  // "auto", "1x1", "4x1", ...
struct GatherBlock {
  int x = 1, y = 1;
};
// The block the gather runs: `requested` (NaiveConfig::gather_block), or auto's choice when empty.
GatherBlock naive_gather_block(std::optional<GatherBlock> requested, const vk::DeviceInfo& device);
// The option itself, for methods that run naive's gather inside them (sprites).
OptionSpec naive_gather_block_option();

// Parses `options` once (naive_config) and makes the filter.
std::unique_ptr<gpu::GpuFilter> make_naive_gpu(gpu::GpuFrame& frame, const FilterOptions& options);

// The gather for any aperture but the disc (naive_shape.hpp): adaptive's tile map (passes tile_max,
// tile_reach; tile_px > 0), each source's colour over its shape's area (pass shape_pack), then the
// gather with the shape test (pass gather). In two halves so that sprites can take its sprites' colour
// out of weighted() between them (its detection pass), as it takes it out of the disc's packed input.
class NaiveShapeGather final : public gpu::GpuFilter {
 public:
  NaiveShapeGather(gpu::GpuFrame& frame, const Aperture& aperture, int tile_px);
  void record(VkCommandBuffer cmd, vk::TimestampQueries& timer) override {
    record_pack(cmd, timer);
    record_gather(cmd, timer);
  }
  void record_pack(VkCommandBuffer cmd, vk::TimestampQueries& timer);
  void record_gather(VkCommandBuffer cmd, vk::TimestampQueries& timer);
  const vk::Buffer& weighted() const { return weighted_; }  // per pixel: (colour / shape area, radius px)
  std::uint64_t intermediate_bytes() const override;
  nlohmann::json stats() override;

 private:
  gpu::GpuFrame& frame_;
  ShapeLattice lattice_;
  std::optional<gpu::CocTilesGpu> tiles_;
  vk::Buffer gauge_, sorted_, weighted_;
  vk::ComputePipeline pack_, gather_;
};

}  // namespace bokeh
