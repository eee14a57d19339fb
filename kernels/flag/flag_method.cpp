// flag: FLAG (Moersch & Hamilton 2014), section 3.2, with reduced-precision and reduced-resolution
// 3D buffers (section 5).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "ceil_div.hpp"
#include "coc_tiles_gpu.hpp"
#include "flag.hpp"
#include "flag_config.hpp"
#include "flag_gpu.hpp"
#include "flag_memory.hpp"
#include "flag_reduced.hpp"
#include "flag_shape.hpp"
#include "flag_shape_gpu.hpp"
#include "flag_tiles.hpp"
#include "method.hpp"
#include "vk/memory.hpp"

namespace bokeh::methods {

namespace {

// The fused pass's tile map (pass tile_max): reads every pixel's radius or area, writes an M a tile.
PassWork fused_tile_max_work(int w, int h) {
  const double pixels = static_cast<double>(w) * h;
  const double tiles = static_cast<double>(ceil_div(w, kFlagFusedTilePx)) * ceil_div(h, kFlagFusedTilePx);
  return {"tile_max", pixels, pixels * 16, tiles * 16};
}

std::vector<PassWork> flag_work(const FlagConfig& c, int w, int h) {
  const int s = c.buffer_scale;
  const GatherPattern low = reduced_pattern(c.pattern, s);
  const double full = static_cast<double>(w) * h, lows = static_cast<double>(ceil_div(w, s)) * ceil_div(h, s);
  const double layer_bytes = lows * low.layers() * bytes_per_texel(c.precision);
  std::vector<PassWork> work;
  if (s > 1) work.push_back({"downsample", full, full * 32, lows * 16});
  if (c.adaptive) {
    // The tile map on FLAG's grid: tile_max reads every radius, tile_reach a (2 R + 1)^2 and
    // tile_layers a (2 R + 1) neighbourhood of tiles. The passes below stay at the worst case's
    // work: a bound; the scene decides how much less they do (stats: adaptive).
    const int t = c.adaptive_tile_px, range = tile_reach_range(low, t);
    const double tiles = static_cast<double>(ceil_div(ceil_div(w, s), t)) * ceil_div(ceil_div(h, s), t);
    work.push_back({"tile_max", lows, lows * 16, tiles * 16});
    work.push_back({"tile_reach", tiles * (2 * range + 1) * (2 * range + 1), tiles * 16, tiles * 16});
    work.push_back({"tile_layers", tiles * (2 * range + 1), tiles * 16, tiles * 16});
  }
  if (is_bracketed(c.precision))
    work.push_back({"bracket", lows * low.size_n, lows * 16,
                    static_cast<double>(flag_bracket_buffer_bytes(ceil_div(h, s), low.layers()))});
  // Every binning reads each pixel's N row samples (scan: as interval ends, loaded once per 8 layers
  // of a segment, the repeats from cache) and writes its layers once.
  if (c.layer_buffer == FlagLayerBuffer::registers) {  // as on_device resolves auto
    // The tile map's M (tile_max reads every radius), which bounds the row samples the fused pass
    // loads; then both passes in one dispatch: the same taps as a bound, and no layer leaves registers.
    if (flag_fused_reads_tile_map(low.layers())) work.push_back(fused_tile_max_work(w, h));
    work.push_back({"fused", 2 * lows * low.size_n, lows * 16, lows * 16, 2 * layer_bytes});
  } else if (c.streamed) {
    // Both passes band by band under one timestamp: the same taps and bytes, the layers through the
    // ring (which a GPU's L2 cache can hold) instead of a frame-sized buffer.
    work.push_back({"streamed", 2 * lows * low.size_n, lows * 16 + layer_bytes, layer_bytes + lows * 16});
  } else {
    work.push_back({"horizontal", lows * low.size_n, lows * 16, layer_bytes});
    work.push_back({"vertical", lows * low.size_n, layer_bytes, lows * 16});
  }
  if (s > 1) work.push_back({"upsample", full * 4, full * 32 + lows * 16, full * 16});
  return work;
}

MemoryUse flag_gpu_memory(const FlagConfig& c, int w, int h, vk::Context* ctx) {
  MemoryUse use;
  if (c.layer_buffer == FlagLayerBuffer::registers) {  // as flag_layers_as_run resolves auto
    // No layer buffer: each invocation's N = 2 n + 1 running sums and a row's bins and layers (n + 1
    // each), 3 floats apiece, live in registers and the driver's stack, not in memory it allocates.
    // The tile map's M alone is allocated.
    use.bytes = gpu::CocTilesGpu::bytes(w, h, kFlagFusedTilePx);
    use.from_driver = ctx != nullptr;
    use.details = {{"layer_buffer_bytes", 0},
                   {"tile_map_bytes", use.bytes},
                   {"registers", {{"floats_per_invocation", 3 * (c.pattern.size_n + 2 * c.pattern.layers())}}}};
    return use;
  }
  FlagBufferExtent e = flag_buffer_extent(w, h, c.pattern, c.buffer_scale);
  int band_rows = 0;
  if (c.streamed) {
    // The ring as the GPU driver sizes it (flag_gpu.cpp), for the worst case's layers; no device:
    // lavapipe's choice.
    const FlagStreamRing ring = flag_stream_ring(e, reduced_pattern(c.pattern, c.buffer_scale).spacing_px,
                                                 c.precision, c.band_rows, ctx ? ctx->info().is_software() : true);
    band_rows = ring.band_rows;
    e = ring.extent;
  }
  const std::uint64_t texels = e.texels() * static_cast<std::uint64_t>(bytes_per_texel(c.precision));
  std::uint64_t layers = texels;
  if (ctx) {
    layers = vk::image_3d_requirement_bytes(*ctx, layer_format(c.precision), e.width, e.height, e.layers);
    use.from_driver = true;
  }
  std::uint64_t other = 0;
  if (is_bracketed(c.precision)) other += flag_bracket_buffer_bytes(e.height, e.layers);
  if (c.buffer_scale > 1) {
    other += 2ull * e.width * e.height * 16;  // low-res packed input and output
    const GatherPattern low = reduced_pattern(c.pattern, c.buffer_scale);
    other += DiscAreaTable(low).by_index().size() * sizeof(std::int32_t);  // the downsample's area table
  }
  // Adaptive: the worst case stays the model (what a budget must allow for); the layers actually
  // allocated follow the scene (the point's memory.allocated_bytes). Plus the tile map.
  if (c.adaptive)
    other += gpu::CocTilesGpu::bytes(static_cast<int>(e.width), static_cast<int>(e.height), c.adaptive_tile_px);
  use.bytes = layers + other;
  const double paper = flag_paper_bytes(w, h, c.pattern, c.precision, c.buffer_scale);
  use.details = {{"extent", {{"width", e.width}, {"height", e.height}, {"layers", e.layers}}},
                 {"bytes_per_texel", bytes_per_texel(c.precision)},
                 {"layer_buffer_bytes", layers},
                 {"texel_bytes", texels},
                 {"paper_convention_bytes", paper},
                 {"other_bytes", other}};
  if (c.streamed) use.details["streamed"] = {{"band_rows", band_rows}, {"ring_rows", e.height}};
  return use;
}

// Output rows per band of the CPU reference for layer_buffer = streamed (the GPU's band; lavapipe's
// auto when band_rows is 0), 0 otherwise: flag_blur needs no layer buffer at any size, and bracketed
// precisions (brackets span rows) and reduced buffers (flag_blur at low resolution) never stream.
int cpu_band_rows(const FlagConfig& c, int w) {
  if (!c.streamed || c.buffer_scale != 1 || is_bracketed(c.precision)) return 0;
  const int reach_rows = c.pattern.half() * c.pattern.spacing_px;
  const std::uint64_t row_bytes = static_cast<std::uint64_t>(w) * c.pattern.layers() * 12;  // f32 rgb
  return flag_stream_band_rows(c.band_rows, true, reach_rows, row_bytes);
}

// The CPU path cpu_reference takes for these options; cpu_work reads the same choice, so the work
// model follows the dispatch. fused: flag_blur's strips (the disc at full resolution, a per-value
// precision, not streamed); whole_buffer: flag_blur_reference (bracketed precisions span rows).
enum class CpuPath { shape, adaptive, reduced, streamed, whole_buffer, fused };
CpuPath cpu_path(const FilterOptions& o, const FlagConfig& c, int width_px) {
  if (!o.aperture.is_disc()) return CpuPath::shape;
  if (c.adaptive) return CpuPath::adaptive;
  if (c.buffer_scale != 1) return CpuPath::reduced;
  if (cpu_band_rows(c, width_px) > 0) return CpuPath::streamed;
  if (is_bracketed(c.precision)) return CpuPath::whole_buffer;
  return CpuPath::fused;
}

// adaptive = on, as the GPU computes it: FLAG on its grid (full or reduced) with the layers the
// scene's largest disc needs (the same image as with ceil(N/2): scene_sized_pattern), then every
// pixel of a tile nothing blurred reaches (D = 0) gets its input instead of its round trip through
// the layers.
Image flag_adaptive_cpu(const CpuInput& in, const FlagConfig& c) {
  const int s = c.buffer_scale;
  const GatherPattern grid = reduced_pattern(c.pattern, s);
  check_layer_input(in.color, c.precision);
  const Image packed = s == 1 ? in.packed : flag_downsample(in.color, in.radius_px, grid, s);
  const CocTiles tiles = coc_tiles(packed, grid, c.adaptive_tile_px);
  const GatherPattern sized = scene_sized_pattern(grid, tiles.scene_max_index);
  FlagConfig sized_config = c;
  sized_config.pattern = sized;
  Image blurred;
  if (const int band = s == 1 ? cpu_band_rows(sized_config, packed.width) : 0; band > 0)
    blurred = flag_blur_streamed(packed, sized, c.precision, band, in.threads);
  else
    blurred = flag_blur(packed, sized, c.precision, in.threads);
  for (int y = 0; y < packed.height; ++y)
    for (int x = 0; x < packed.width; ++x) {
      if (tiles.reach_index[static_cast<std::size_t>(tiles.tile_of(x, y))] != 0) continue;
      const float* src = packed.px(x, y);
      const bool inside = in_disc(src[3] * src[3], 0, 0);
      for (int c = 0; c < 3; ++c) blurred.px(x, y)[c] = 0.0f + (inside ? src[c] : 0.0f);
    }
  if (in.stats) {
    nlohmann::json stats = coc_tiles_stats(tiles, grid, packed.width, packed.height);
    stats["layers"] = sized.layers();
    stats["layers_worst_case"] = grid.layers();
    stats["scene_max_disc_index_when_prepared"] = tiles.scene_max_index;
    (*in.stats)["adaptive"] = stats;
  }
  return s == 1 ? blurred : flag_upsample(blurred, in.color, in.radius_px, s);
}

// What the method's models and CPU reference assume without a device: lavapipe (a CPU device).
const vk::DeviceInfo& software_device() {
  static const vk::DeviceInfo device = [] {
    vk::DeviceInfo d;
    d.type = "cpu";
    d.subgroup_operations = kFlagScanSubgroupOperations;
    return d;
  }();
  return device;
}

// How the CPU reference sums a non-disc aperture's horizontal pass, as lavapipe would (the reference has
// no device): by chords where its layers are in registers (layer_buffer auto there, which bins by
// chords), in the scan's order where the 3D buffer's binning resolves to scan.
FlagShapeSums cpu_shape_sums(const FilterOptions& o, const FlagConfig& c, const FlagShapeTable& table) {
  if (flag_layer_buffering(o, &software_device()) == FlagLayerBuffer::registers) return FlagShapeSums::chords;
  return flag_shape_binning(c.horizontal_bins, software_device(), table.layers()) == FlagHorizontalBins::scan
             ? FlagShapeSums::scan
             : FlagShapeSums::chords;
}

// The options with layer_buffer as `device` runs it (Method::on_device; device null: the full buffer).
FilterOptions flag_layers_as_run(const FilterOptions& o, const vk::DeviceInfo* device) {
  FilterOptions as_run = o;  // the enumerators are in the order of the option's choices
  as_run.values["layer_buffer"] = static_cast<double>(flag_layer_buffering(o, device));
  return as_run;
}

// A non-disc aperture (flag_shape.hpp): the layers (N unless the shape is mirror-symmetric; streamed:
// the ring's rows) as the driver allocates them, the shape-weighted input (vec4 a pixel), naive's
// sorted gauges and the horizontal pass's table (chords, or row sections for the scan).
MemoryUse flag_shape_gpu_memory(const FlagConfig& c, const Aperture& aperture, int w, int h, vk::Context* ctx) {
  const int layer_count = flag_aperture_layers(aperture, c.pattern);
  // Streamed: the ring as the GPU driver sizes it; no device: lavapipe's choice.
  const FlagStreamRing ring = flag_shape_layer_rows(c, layer_count, w, h, ctx ? ctx->info().is_software() : true);
  const FlagBufferExtent& e = ring.extent;
  MemoryUse use;
  // layer_buffer = registers: no layer buffer, the chord table.
  const bool registers = c.layer_buffer == FlagLayerBuffer::registers;
  const std::uint64_t texels = registers ? 0 : e.texels() * static_cast<std::uint64_t>(bytes_per_texel(c.precision));
  std::uint64_t layers = texels;
  if (ctx && !registers)
    layers = vk::image_3d_requirement_bytes(*ctx, layer_format(c.precision), e.width, e.height, e.layers);
  use.from_driver = ctx != nullptr;
  // The horizontal pass's table: the row sections (scan) or the chords, as the binning resolves on
  // this device (no device: lavapipe's choice).
  const bool halved = layer_count == c.pattern.layers();
  const bool scan = !registers && flag_shape_binning(c.horizontal_bins, ctx ? ctx->info() : software_device(),
                                                     layer_count) == FlagHorizontalBins::scan;
  const std::uint64_t weighted = static_cast<std::uint64_t>(w) * h * 16,
                      tables = c.pattern.samples_per_pixel() * sizeof(float) +
                               FlagShapeTable::bytes_for(c.pattern, layer_count, scan);
  // Registers: the map of areas the fused pass reads (made whether or not it is read).
  const std::uint64_t map = registers ? gpu::CocTilesGpu::bytes(w, h, kFlagFusedTilePx) : 0;
  use.bytes = layers + weighted + tables + map;
  use.details = {{"extent", {{"width", e.width}, {"height", e.height}, {"layers", e.layers}}},
                 {"bytes_per_texel", bytes_per_texel(c.precision)},
                 {"layer_buffer_bytes", layers},
                 {"texel_bytes", texels},
                 {"aperture", aperture.name()},
                 {"layer_halves", halved ? 1 : 2},
                 {"horizontal_table", scan ? "row sections" : "chords"},
                 {"paper_convention_bytes", static_cast<double>(texels)},
                 {"tile_map_bytes", map},
                 {"other_bytes", weighted + tables + map}};
  if (c.streamed) use.details["streamed"] = {{"band_rows", ring.band_rows}, {"ring_rows", e.height}};
  return use;
}

// Why FLAG cannot draw a non-disc aperture with these options ("" when it can): the per-value
// precisions at full resolution, adaptive off, any binning, full or streamed layers.
std::string flag_shape_unsupported(const FilterOptions& o) {
  if (o.aperture.is_disc()) return "";
  const FlagConfig c = flag_config(o);
  std::vector<std::string> why;
  if (is_bracketed(c.precision)) why.push_back("precision " + o.precision);
  if (c.buffer_scale != 1) why.push_back(fmt::format("buffer scale {}", c.buffer_scale));
  if (c.adaptive) why.push_back("adaptive = on");
  if (why.empty()) return "";
  return fmt::format("flag draws the aperture {} with f32, f16 or r11g11b10f layers, buffer scale 1 and adaptive "
                     "off (any horizontal_bins, full, streamed or registers layers), not with {}",
                     o.aperture.name(), fmt::join(why, ", "));
}

// The method's own options (flag_config parses them).
std::vector<OptionSpec> flag_options() {
  return {{"horizontal_block",
           "flag: pixels per GPU invocation of the horizontal pass, at stride k (auto: 4 on CPU devices such as "
           "lavapipe, 1 on GPUs; every block gives the same image)",
           0, 0, 0, false, flag_horizontal_blocks()},
          {"horizontal_bins",
           "flag: how the GPU horizontal pass bins each row sample into the layer its disc reaches. indexed: "
           "bins[z] += sample (one add per sample, the paper's O(N + n)); masked: every bin tests the sample "
           "and adds it or -0.0 (O(N n) adds, no dynamically indexed array: lavapipe makes that a scalar load "
           "and store per lane); scan: per layer, interval sums by a prefix scan along row segments (O(N), "
           "each sample loaded once per 8 layers and handed on by subgroup shuffle; the same samples in another "
           "order of additions; needs subgroup ballot and shuffle); auto: on CPU devices such as lavapipe, with "
           "the layers in registers (layer_buffer auto there), masked up to 24 layers (N = 47), indexed beyond "
           "(scan runs as indexed there); with the 3D buffer masked up to 12 layers (N = 23), scan beyond "
           "(other apertures: scan from 7 layers, else indexed); indexed on GPUs. indexed and masked give the "
           "same image bit for bit, scan to f32 rounding",
           0, 0, 0, false, flag_horizontal_bins()},
          {"vertical_order",
           "flag: the order the GPU vertical pass's workgroups take their tiles. rows: row-major; columns: down "
           "8-px column strips, so a layer row's second read (by the output row 2 j k below its first) finds it "
           "in cache; auto: columns on CPU devices such as lavapipe, rows on GPUs. Every order gives the same "
           "image bit for bit",
           0, 0, 0, false, flag_vertical_orders()},
          adaptive_option("flag, off: a ceil(N/2)-layer 3D buffer and every pixel's gather over the whole "
                          "pattern (the worst case); on: layers for the scene's largest radius (reduced on the "
                          "GPU when the run is prepared, one int read back), a tile-max CoC map bounding each "
                          "workgroup's row samples and each tile's layers, and tiles nothing blurred reaches "
                          "output their input: the worst case's image bit for bit (f32; with scan bins, to f32 "
                          "rounding: a layer nothing reaches keeps the scan's rounding residue, which the worst "
                          "case adds and adaptive skips), or up to one rounding of the layer format in those "
                          "tiles"),
          adaptive_tile_option(),
          {"layer_buffer",
           "flag: where the horizontal pass leaves the layers for the vertical pass. full: the paper's 3D buffer "
           "(W x H x ceil(N/2) texels; the reference); streamed: a ring of B + 2 n k rows filled band by band "
           "(B = --band-rows output rows a band), the two passes alternating per band in one command buffer: "
           "the full buffer's image bit for bit in a fraction of its memory; registers: no buffer, both passes "
           "fused, each invocation walking down a column with the layers in registers (buffer scale 1, f32 or "
           "f16, adaptive off; loading only the row samples the tile-max CoC map lets reach its columns): "
           "the CPU reference's image bit for bit (which sums a polygon by chords where lavapipe runs it in "
           "registers), for CPU devices (lavapipe stores and loads a texel lane by lane); auto (the default): "
           "registers where it runs on a CPU device, any aperture, else full",
           0, 0, 0, false, flag_layer_buffers(), {1, 2, 3}},
          {"band_rows",
           "flag, layer_buffer = streamed: output rows per band (0: auto, the largest band whose ring fits 16 MiB "
           "on CPU devices such as lavapipe and 32 MiB on GPUs, at least 8 rows). Fewer rows: less memory, more "
           "dispatches (two a band); the image is the same for every value",
           0, 0, 1 << 16, true, {}}};
}

// The CPU reference's intermediates, by the path it takes (cpu_path).
std::uint64_t flag_cpu_memory_bytes(const FilterOptions& o, int w, int h) {
  const FlagConfig c = flag_config(o);
  if (!o.aperture.is_disc()) {  // the packed input (4 floats a pixel) and the whole 3D buffer in f32
    return static_cast<std::uint64_t>(w) * h * (16 + flag_aperture_layers(o.aperture, c.pattern) * std::uint64_t{12});
  }
  if (const int band = cpu_band_rows(c, w); band > 0)
    return flag_streamed_cpu_bytes(w, h, c.pattern, band, default_cpu_threads());
  // flag_blur on the grid (reduced: the low-resolution input, 4 floats a pixel, and blur, 3, besides),
  // or for bracketed precisions flag_blur_reference's whole 3D buffer in f32.
  const GatherPattern low = reduced_pattern(c.pattern, c.buffer_scale);
  const auto lw = static_cast<std::uint64_t>(ceil_div(w, c.buffer_scale));
  const auto lh = static_cast<std::uint64_t>(ceil_div(h, c.buffer_scale));
  const std::uint64_t low_images = c.buffer_scale == 1 ? 0 : lw * lh * 7 * sizeof(float);
  if (is_bracketed(c.precision)) return low_images + lw * lh * low.layers() * 3 * sizeof(float);
  return low_images + flag_blur_cpu_bytes(static_cast<int>(lw), static_cast<int>(lh), low, default_cpu_threads());
}

}  // namespace

void declare_flag(std::vector<Method>& methods) {
  Method m;
  m.name = "flag";
  m.description = "FLAG: horizontal pass into a ceil(N/2)-layer 3D buffer, vertical pass (FLAG paper 3.2)";
  for (LayerPrecision p : all_layer_precisions()) m.precisions.push_back(to_string(p));
  // The paper's RGBA16F first: the default.
  std::swap(m.precisions[0], m.precisions[1]);
  m.buffer_scales = flag_buffer_scales();
  m.options = flag_options();
  // Every function below parses the options once (flag_config) and reads only the FlagConfig.
  m.device = [](const FilterOptions& o) {
    const FlagConfig c = flag_config(o);
    vk::DeviceRequirements needs;
    needs.storage_image_3d_formats = {layer_format(c.precision)};
    if (c.adaptive) needs.subgroup_operations |= VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;  // the tile map's bound, shared
    // An explicit scan or registers (the same sample hand-over); auto takes them only where they run.
    if (c.horizontal_bins == FlagHorizontalBins::scan || c.layer_buffer == FlagLayerBuffer::registers)
      needs.subgroup_operations |= kFlagScanSubgroupOperations;
    return needs;
  };
  // Any convex aperture by per-layer chord extents (flag_shape.hpp); flag_shape_unsupported says with what.
  m.aperture_unsupported = flag_shape_unsupported;
  m.unsupported = [](const FilterOptions& o, int, int) {
    return o.choice<FlagLayerBuffer>("layer_buffer") == FlagLayerBuffer::registers ? flag_registers_unsupported(o)
                                                                                   : std::string();
  };
  m.cpu_reference = [](const CpuInput& in) {
    const FlagConfig c = flag_config(in.options);
    switch (cpu_path(in.options, c, in.packed.width)) {
      case CpuPath::shape: {
        const FlagShapeTable table(in.options.aperture, c.pattern);
        return flag_shape_blur(in.color, in.radius_px, table, c.pattern, c.precision, in.threads,
                               cpu_shape_sums(in.options, c, table));
      }
      case CpuPath::adaptive: return flag_adaptive_cpu(in, c);
      case CpuPath::reduced:
        return flag_reduced_blur(in.color, in.radius_px, c.pattern, c.buffer_scale, c.precision, in.threads);
      case CpuPath::streamed:
        return flag_blur_streamed(in.packed, c.pattern, c.precision, cpu_band_rows(c, in.packed.width), in.threads);
      case CpuPath::whole_buffer: return flag_blur_reference(in.packed, c.pattern, c.precision, in.threads);
      case CpuPath::fused: break;
    }
    return flag_blur(in.packed, c.pattern, c.precision, in.threads);
  };
  m.make_gpu = [](gpu::GpuFrame& frame, const FilterOptions& o) {
    return o.aperture.is_disc() ? make_flag_gpu(frame, o) : make_flag_shape_gpu(frame, o);
  };
  m.on_device = flag_layers_as_run;
  m.work = [](const FilterOptions& o, int w, int h) {
    const FlagConfig c = flag_config(o);
    if (o.aperture.is_disc()) return flag_work(c, w, h);
    // A shape: the weights (colour and radius in, a search in the sorted gauges), then both passes
    // over N row / column samples, through N layers unless the shape is mirror-symmetric.
    const double pixels = static_cast<double>(w) * h;
    const double layer_bytes = pixels * flag_aperture_layers(o.aperture, c.pattern) * bytes_per_texel(c.precision);
    std::vector<PassWork> work = {{"shape_pack", pixels, pixels * 32, pixels * 16}};
    if (c.layer_buffer == FlagLayerBuffer::registers) {  // both passes in one, no layers (flag_work)
      if (flag_fused_reads_tile_map(c.pattern.layers(), true)) work.push_back(fused_tile_max_work(w, h));  // areas
      work.push_back({"fused", 2 * pixels * c.pattern.size_n, pixels * 16, pixels * 16, 2 * layer_bytes});
    } else if (c.streamed) {  // both passes band by band under one timestamp (flag_work)
      work.push_back({"streamed", 2 * pixels * c.pattern.size_n, pixels * 16 + layer_bytes, layer_bytes + pixels * 16});
    } else {
      work.insert(work.end(), {{"horizontal", pixels * c.pattern.size_n, pixels * 16, layer_bytes},
                               {"vertical", pixels * c.pattern.size_n, layer_bytes, pixels * 16}});
    }
    return work;
  };
  // flag_blur (the disc at full resolution, per-value precisions) keeps each layer in its strip's
  // scratch, within a core's L2 (flag_blur_cpu_bytes): both passes' taps, the packed input read and the
  // image (3 floats a pixel) written once; it keeps what the whole-buffer path moves, the layers at
  // the precision's texel. Every other CPU path moves its layers as the GPU passes do.
  m.cpu_work = [gpu_work = m.work](const FilterOptions& o, int w, int h) {
    const FlagConfig c = flag_config(o);
    if (cpu_path(o, c, w) != CpuPath::fused) return gpu_work(o, w, h);
    const double pixels = static_cast<double>(w) * h;
    const double layer_bytes = pixels * c.pattern.layers() * bytes_per_texel(c.precision);
    return std::vector<PassWork>{{"fused", 2 * pixels * c.pattern.size_n, pixels * 16, pixels * 12, 2 * layer_bytes}};
  };
  m.gpu_memory = [](const FilterOptions& o, int w, int h, vk::Context* ctx) {
    // The layers as the device runs them (no device: the full buffer).
    const FlagConfig c = flag_config(flag_layers_as_run(o, ctx ? &ctx->info() : nullptr));
    return o.aperture.is_disc() ? flag_gpu_memory(c, w, h, ctx) : flag_shape_gpu_memory(c, o.aperture, w, h, ctx);
  };
  m.cpu_memory_bytes = flag_cpu_memory_bytes;
  // Against the CPU emulation of the same format. Each output sums 2n+1 non-negative layer values,
  // none larger than the image's largest output (layer 0 of the pixel's own row is part of it):
  //   f32: summation order only; f16 / r11g11b10f: one ulp per stored value (Vulkan lets the GPU round
  //   toward zero where the CPU rounds to nearest): 2^-10 / 2^-5 (blue) of the output; bracketed:
  //   one code per value, (2n+1) / levels of the largest value. Doubled for the bilinear upsample of
  //   reduced buffers (a low-res value can exceed the full-res output it feeds by up to 2x).
  m.gpu_tolerance = [](const FilterOptions& o) {
    const FlagConfig c = flag_config(o);
    const GatherPattern low = reduced_pattern(c.pattern, c.buffer_scale);
    const double upsample = c.buffer_scale > 1 ? 2.0 : 1.0;
    switch (c.precision) {
      case LayerPrecision::f32: return 1e-5;
      case LayerPrecision::f16: return upsample * std::ldexp(1.0, -10) + 1e-5;
      case LayerPrecision::r11g11b10f: return upsample * std::ldexp(1.0, -5) + 1e-5;
      default: return upsample * low.size_n / bracket_levels(c.precision) + 1e-5;
    }
  };
  // Storage, per output value relative to the largest: a GPU may round each stored layer value
  // either way (Vulkan allows it): one ulp of the output, 2^-10 (f16) or 2^-5 (r11g11b10f's blue);
  // bracketed: one code of each of the 2n+1 values summed. The reduced buffers' downsample and
  // upsample conserve energy (the bilinear tent weights sum to one per low-res pixel) and are exact
  // at radius 0 (every source below s / 2 stays at full resolution).
  m.storage_tolerance = [](const FilterOptions& o) {
    const FlagConfig c = flag_config(o);
    switch (c.precision) {
      case LayerPrecision::f32: return 0.0;
      case LayerPrecision::f16: return std::ldexp(1.0, -10);
      case LayerPrecision::r11g11b10f: return std::ldexp(1.0, -5);
      default:
        return static_cast<double>(reduced_pattern(c.pattern, c.buffer_scale).size_n) / bracket_levels(c.precision);
    }
  };
  // An isolated highlight in focus is stored as it is (its disc's area is 1), so the layer format's
  // largest finite value bounds it: f16 65504, r11g11b10f blue's (2 - 2^-5) 2^15 = 64512 (red and
  // green reach 65024). f32 and the bracketed formats (offsets and scales in f32) have f32's range.
  m.input_limit = [](const FilterOptions& o) {
    switch (flag_config(o).precision) {
      case LayerPrecision::f16: return 65504.0;
      case LayerPrecision::r11g11b10f: return 64512.0;
      default: return static_cast<double>(std::numeric_limits<float>::max());
    }
  };
  m.energy_note = "the same sums as naive (each source's contributions sum to its colour), up to the layers' storage";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
