#include "coc_tiles_gpu.hpp"

#include <algorithm>
#include <vector>

#include "ceil_div.hpp"
#include "vk/spirv.hpp"

namespace bokeh {

OptionSpec adaptive_option(const std::string& help) { return {"adaptive", help, 0, 0, 0, false, {"off", "on"}}; }

bool adaptive_on(const FilterOptions& options) {
  return options.values.contains("adaptive") && options.choice<AdaptiveMode>("adaptive") == AdaptiveMode::on;
}

OptionSpec adaptive_tile_option() {
  return {"adaptive_tile_px",
          "adaptive = on: side of the tile-max CoC map's tiles in px (of the grid the passes run on). Smaller tiles "
          "follow the CoC more closely but cost more map work (tile_reach visits ~(2 n k / tile + 3)^2 tiles each); "
          "the lanes of a subgroup share the largest bound of their pixels' tiles, so tiles much smaller than a "
          "subgroup's pixels gain little (lavapipe, 800x600: 8 and 16 alike, 32 slower)",
          16, 4, 128, true, {}};
}

int adaptive_tile_px(const FilterOptions& options) {
  const auto it = options.values.find("adaptive_tile_px");
  return it == options.values.end() ? static_cast<int>(adaptive_tile_option().default_value) : static_cast<int>(it->second);
}

nlohmann::json coc_tiles_stats(const CocTiles& t, const GatherPattern& p, int width_px, int height_px) {
  const DiscAreaTable areas(p);
  const auto& by_index = areas.by_index();
  std::size_t passed = 0;
  double samples = 0;
  for (int ty = 0; ty < t.tiles_y; ++ty)
    for (int tx = 0; tx < t.tiles_x; ++tx) {
      const int d = t.reach_index[static_cast<std::size_t>(ty) * t.tiles_x + tx];
      const double pixels = static_cast<double>(std::min(t.tile_px, width_px - tx * t.tile_px)) *
                            std::min(t.tile_px, height_px - ty * t.tile_px);
      if (d == 0) ++passed;
      samples += pixels * by_index[static_cast<std::size_t>(std::clamp(d, 0, areas.max_index()))];
    }
  const double worst = static_cast<double>(width_px) * height_px * p.samples_per_pixel();
  return {{"tile_px", t.tile_px},
          {"tiles", t.reach_index.size()},
          {"tiles_passed_through", passed},
          {"scene_max_disc_index", t.scene_max_index},
          {"gather_sample_fraction", worst > 0 ? samples / worst : 0.0}};
}

namespace gpu {

namespace {
constexpr VkDescriptorType kBuffer = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}  // namespace

std::uint64_t CocTilesGpu::bytes(int width_px, int height_px, int tile_px) {
  const auto tiles = static_cast<std::uint64_t>(ceil_div(width_px, tile_px)) * ceil_div(height_px, tile_px);
  return (tiles + 1) * 16;
}

CocTilesGpu::CocTilesGpu(vk::Context& ctx, const vk::Buffer& packed, std::uint32_t width_px, std::uint32_t height_px,
                         int spacing_px, int tile_px, bool areas)
    : ctx_(ctx),
      tile_px_(tile_px),
      buffer_(vk::make_storage_buffer(ctx, bytes(static_cast<int>(width_px), static_cast<int>(height_px), tile_px),
                                      "tile-max CoC map")),
      tile_max_(ctx, vk::spirv("common/tile_max"), {kBuffer, kBuffer}, sizeof(PassParams), {spacing_px, tile_px, areas}),
      tile_reach_(ctx, vk::spirv("common/tile_reach"), {kBuffer}, sizeof(PassParams), {spacing_px, tile_px}) {
  tile_max_.bind(0, packed);
  tile_max_.bind(1, buffer_);
  tile_reach_.bind(0, buffer_);
}

void CocTilesGpu::record(VkCommandBuffer cmd, vk::TimestampQueries* timer, const PassParams& grid) const {
  // The scene maximum is an atomicMax: reset it (the previous pass's barrier covers transfer writes).
  vkCmdFillBuffer(cmd, buffer_.get(), 0, 16, 0u);
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                       nullptr, 0, nullptr);
  record_max(cmd, timer, grid);
  dispatch_per_tile(cmd, tile_reach_, grid);
  if (timer) timer->end_pass(cmd, "tile_reach");
}

void CocTilesGpu::record_max(VkCommandBuffer cmd, vk::TimestampQueries* timer, const PassParams& grid) const {
  dispatch_per_tile(cmd, tile_max_, grid);
  if (timer) timer->end_pass(cmd, "tile_max");
}

void CocTilesGpu::dispatch_per_tile(VkCommandBuffer cmd, const vk::ComputePipeline& pass,
                                    const PassParams& grid) const {
  pass.dispatch(cmd, &grid, static_cast<std::uint32_t>(ceil_div(grid.width_px, tile_px_)),
                static_cast<std::uint32_t>(ceil_div(grid.height_px, tile_px_)));
}

int CocTilesGpu::read_scene_max_index() const {
  std::int32_t first[4] = {};
  vk::download(ctx_, buffer_, first, sizeof(first));
  return first[0];
}

CocTiles CocTilesGpu::read(int width_px, int height_px, std::vector<int>* write_layers) const {
  CocTiles t;
  t.tile_px = tile_px_;
  t.tiles_x = ceil_div(width_px, tile_px_);
  t.tiles_y = ceil_div(height_px, tile_px_);
  const std::size_t count = static_cast<std::size_t>(t.tiles_x) * t.tiles_y;
  std::vector<std::int32_t> raw((count + 1) * 4);
  vk::download(ctx_, buffer_, raw.data(), raw.size() * sizeof(std::int32_t));
  t.scene_max_index = raw[0];
  t.max_index.resize(count);
  t.reach_index.resize(count);
  if (write_layers) write_layers->resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    t.max_index[i] = raw[(i + 1) * 4];
    t.reach_index[i] = raw[(i + 1) * 4 + 1];
    if (write_layers) (*write_layers)[i] = raw[(i + 1) * 4 + 2];
  }
  return t;
}

}  // namespace gpu
}  // namespace bokeh
