// naive: the quadratic gather of the FLAG paper, section 3.1.
#include <optional>
#include <string>

#include "coc_tiles_gpu.hpp"
#include "method.hpp"
#include "naive_config.hpp"
#include "naive_gather.hpp"
#include "naive_gpu.hpp"
#include "naive_shape.hpp"

namespace bokeh::methods {

void declare_naive(std::vector<Method>& methods) {
  Method m;
  m.name = "naive";
  m.description = "naive quadratic gather, N x N samples at spacing k (FLAG paper 3.1)";
  m.precisions = {"f32"};
  // Same output for every block (bit for bit: each output adds its samples in the same order); only
  // the speed differs, by device. See shaders/naive/gather.comp. Likewise adaptive = on.
  m.options = {naive_gather_block_option(),
               adaptive_option("off: every pixel gathers the pattern's largest disc (the worst case); on: model only "
                               "what the scene requires: a tile-max CoC map (passes tile_max, tile_reach) bounds each "
                               "pixel's gather by the largest disc that can reach its tile, tiles nothing blurred "
                               "reaches output their input, and FLAG allocates the layers the scene's largest radius "
                               "needs (found on the GPU when the run is prepared). The image is the worst case's (naive: "
                               "bit for bit; FLAG: up to one rounding of the layer format where a tile passes its input "
                               "through)"),
               adaptive_tile_option()};
  // Adaptive: the tile map's bound is shared across a subgroup (subgroupMax, shaders/common/tiles.glsl).
  // Every function below parses the options once (naive_config) and reads only the NaiveConfig.
  m.device = [](const FilterOptions& o) {
    vk::DeviceRequirements needs;
    if (naive_config(o).adaptive) needs.subgroup_operations = VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;
    return needs;
  };
  // Any aperture (issue 23): a shape test per sample against the aperture's gauge of its offset, weights
  // 1 / the shape's area on the pattern (naive_shape.hpp). Adaptive = on too: every shape lies inside
  // the disc of its radius (exactly, in floats: ShapeLattice), so the tile map's disc bound holds for it
  // and the image is adaptive = off's, bit for bit.
  m.aperture_unsupported = [](const FilterOptions&) { return std::string(); };
  m.cpu_reference = [](const CpuInput& in) {
    const NaiveConfig c = naive_config(in.options);
    std::optional<CocTiles> tiles;
    if (c.adaptive) {
      tiles = coc_tiles(in.packed, in.options.pattern, c.adaptive_tile_px);
      if (in.stats)
        (*in.stats)["adaptive"] = coc_tiles_stats(*tiles, in.options.pattern, in.packed.width, in.packed.height);
    }
    const CocTiles* bound = tiles ? &*tiles : nullptr;
    if (!in.options.aperture.is_disc())
      return naive_shape_gather(in.color, in.radius_px, ShapeLattice(in.options.aperture, in.options.pattern),
                                in.options.pattern, in.threads, bound);
    return naive_gather(in.packed, in.options.pattern, in.threads, bound);
  };
  m.make_gpu = make_naive_gpu;
  // Every pixel tests all N x N samples; it reads the packed image and writes the output once.
  // Adaptive: the tile map's passes (tile_max reads every radius, tile_reach a (2 R + 1)^2
  // neighbourhood of tiles), and the gather's N x N as the bound it is: the scene decides how much
  // less it visits (stats: adaptive.gather_sample_fraction).
  m.work = [](const FilterOptions& o, int w, int h) {
    const NaiveConfig c = naive_config(o);
    const double pixels = static_cast<double>(w) * h;
    std::vector<PassWork> work;
    if (c.adaptive) {
      const int t = c.adaptive_tile_px, range = tile_reach_range(o.pattern, t);
      const double tiles = static_cast<double>((w + t - 1) / t) * ((h + t - 1) / t);
      work.push_back({"tile_max", pixels, pixels * 16, tiles * 16});
      work.push_back({"tile_reach", tiles * (2 * range + 1) * (2 * range + 1), tiles * 16, tiles * 16});
    }
    // Any other aperture: the weights first (colour and radius in, a binary search in the sorted gauges).
    if (!o.aperture.is_disc()) work.push_back({"shape_pack", pixels, pixels * 32, pixels * 16});
    work.push_back({"gather", pixels * o.pattern.samples_per_pixel(), pixels * 16, pixels * 16});
    return work;
  };
  m.gpu_memory = [](const FilterOptions& o, int w, int h, vk::Context*) {
    const NaiveConfig c = naive_config(o);
    MemoryUse use;
    const std::uint64_t tile_map = c.adaptive ? gpu::CocTilesGpu::bytes(w, h, c.adaptive_tile_px) : 0;
    use.bytes = tile_map;
    use.details = {{"tile_map_bytes", tile_map}};
    if (!o.aperture.is_disc()) {  // the shape-weighted colour (vec4 a pixel) and two float tables of N x N
      const auto side = static_cast<std::uint64_t>(o.pattern.size_n);
      const std::uint64_t weighted = static_cast<std::uint64_t>(w) * h * 16, tables = 2 * side * side * 4;
      use.bytes += weighted + tables;
      use.details["weighted_bytes"] = weighted;
      use.details["gauge_tables_bytes"] = tables;
    }
    return use;
  };
  m.cpu_memory_bytes = [](const FilterOptions& o, int w, int h) {
    const NaiveConfig c = naive_config(o);
    std::uint64_t bytes = o.aperture.is_disc() ? 0 : static_cast<std::uint64_t>(w) * h * 16;  // the weighted colour
    if (c.adaptive) {
      const auto t = static_cast<std::uint64_t>(c.adaptive_tile_px);
      bytes += (static_cast<std::uint64_t>(w) + t - 1) / t * ((static_cast<std::uint64_t>(h) + t - 1) / t) * 8;
    }
    return bytes;
  };
  // The same sums in the same order as the CPU: only f32 rounding of the GPU's fused operations.
  m.gpu_tolerance = [](const FilterOptions&) { return 1e-5; };
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  m.energy_note = "each source's contributions sum to its colour: weights are 1 / the discrete disc area";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
