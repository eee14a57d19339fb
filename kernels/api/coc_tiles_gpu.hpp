#pragma once
// What the methods with an adaptive mode share: the option itself, and the tile-max CoC map on the
// GPU (shaders/common/tile_max.comp, tile_reach.comp; definitions and CPU twin in
// kernels/core/coc_tiles.hpp).
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "coc_tiles.hpp"
#include "gpu_frame.hpp"
#include "method.hpp"

namespace bokeh {

// The option every method with an adaptive mode declares, with this key and these choices
// ("off": sized for the worst case, today's behaviour; "on": only what the scene requires), so
// commands (`bokehbench adaptive`) find those methods through the registry. `help` says what it does
// in that method.
OptionSpec adaptive_option(const std::string& help);
// Its value; the enumerators in the order of adaptive_option()'s choices.
enum class AdaptiveMode { off, on };
// True when `options` has adaptive = on (false without the option: e.g. sprites running naive's gather).
bool adaptive_on(const FilterOptions& options);
// The tile size of the tile-max CoC map, "adaptive_tile_px".
OptionSpec adaptive_tile_option();
int adaptive_tile_px(const FilterOptions& options);  // the default without the option

// What a scene's tile map says, with the keys the adaptive methods' stats() and CPU references use:
// tile_px, tiles, tiles_passed_through (D = 0: output = input), scene_max_disc_index, and
// gather_sample_fraction: sum over pixels of the samples inside their tile's disc of index D over
// the pattern's N^2 (what a per-tile gather visits, against the worst case).
nlohmann::json coc_tiles_stats(const CocTiles& tiles, const GatherPattern& pattern, int width_px, int height_px);

namespace gpu {

class CocTilesGpu {
 public:
  // Over a width x height grid (the frame's, or FLAG's reduced one) whose packed input (rgb / area,
  // radius) is `packed`. `areas`: the input's .a is a polygon's area (FLAG's shape_pack), and M the
  // tiles' largest area (tile_max only).
  CocTilesGpu(vk::Context& ctx, const vk::Buffer& packed, std::uint32_t width_px, std::uint32_t height_px,
              int spacing_px, int tile_px, bool areas = false);

  // Records the reset of the scene maximum, then tile_max and tile_reach over `grid` (its region,
  // n and k), each stamped with its name when `timer` is given.
  void record(VkCommandBuffer cmd, vk::TimestampQueries* timer, const PassParams& grid) const;
  // Records tile_max alone: each tile's M, what FLAG's fused pass reads (no D, no scene maximum).
  void record_max(VkCommandBuffer cmd, vk::TimestampQueries* timer, const PassParams& grid) const;
  const vk::Buffer& buffer() const { return buffer_; }
  int tile_px() const { return tile_px_; }
  std::uint64_t allocated_bytes() const { return buffer_.allocated_bytes(); }
  // Bytes of the map for a width x height grid: an ivec4 per tile and one for the scene maximum.
  static std::uint64_t bytes(int width_px, int height_px, int tile_px);

  // After a recorded frame: the scene's largest disc index, one int read back.
  int read_scene_max_index() const;
  // After a recorded frame, outside any timing: M and D of every tile of the width x height grid
  // the frame covered, and FLAG's Z (.z) when asked for.
  CocTiles read(int width_px, int height_px, std::vector<int>* write_layers = nullptr) const;

 private:
  // One invocation per tile of `grid`.
  void dispatch_per_tile(VkCommandBuffer cmd, const vk::ComputePipeline& pass, const PassParams& grid) const;

  vk::Context& ctx_;
  int tile_px_;
  vk::Buffer buffer_;
  vk::ComputePipeline tile_max_, tile_reach_;
};

}  // namespace gpu
}  // namespace bokeh
