// `bokehbench memory`: FLAG's 3D buffer size in the paper's convention and as the driver allocates it,
// and the streamed layers' ring (layer_buffer = streamed) beside it, one row per --band-rows. With
// --aperture, the layers FLAG keeps for that shape (flag_shape.hpp: N unless mirror-symmetric), in the
// full buffer at scale 1 (the streamed ring of a shape: `flag`'s gpu_memory, tested beside the driver).
#include <fmt/format.h>

#include "commands.hpp"
#include "flag_memory.hpp"
#include "flag_gpu.hpp"
#include "flag_shape.hpp"
#include "method.hpp"
#include "report.hpp"
#include "sweep.hpp"
#include "vk/memory.hpp"

namespace bokeh {

namespace {

struct MemoryOptions {
  AxisFlags axes;
  int width_px = 0, height_px = 0, size_n = 0;  // from axes (memory() sets them)
  std::string device, out_path = "results/memory.json";
  std::vector<int> band_rows = {0};  // streamed rows: band heights (0: the device's auto)
  Aperture aperture;                 // from axes (memory() sets it)
};

// The figures the paper prints (sections 3.2.4 and 5), for comparison only: 1080p, 41x41, RGBA16F.
double paper_printed_mb(const MemoryOptions& o, LayerPrecision precision, int scale) {
  if (o.width_px != 1920 || o.height_px != 1080 || o.size_n != 41 || precision != LayerPrecision::f16 ||
      !o.aperture.is_disc())
    return 0;
  return scale == 1 ? 332.0 : scale == 2 ? 42.0 : 5.2;
}

void memory(MemoryOptions& o) {
  o.axes.resolve();
  const Resolution frame = o.axes.frame_sizes().front();
  o.width_px = frame.width_px, o.height_px = frame.height_px;
  o.size_n = o.axes.patterns().front().size_n;  // the buffer does not depend on the spacing
  o.aperture = o.axes.aperture_shapes().front();
  check_writable_file(o.out_path);
  vk::Context ctx(o.device);
  nlohmann::json rows = nlohmann::json::array();
  const GatherPattern pattern{o.size_n, 2};
  validate(pattern);
  // A non-disc aperture: its layers, at scale 1 and full only (what FLAG draws it with).
  const int layers = flag_aperture_layers(o.aperture, pattern);
  const bool shape = !o.aperture.is_disc();
  fmt::print("FLAG 3D buffer, {}x{}, {}x{} gather ({} layers), aperture {}, device {}\n", o.width_px, o.height_px,
             o.size_n, o.size_n, layers, o.aperture.name(), ctx.info().name);
  if (shape)
    fmt::print("  {} layers: {} (full buffer, scale 1)\n", o.aperture.name(),
               layers == pattern.layers() ? "one half, mirror-symmetric" : "both halves, not mirror-symmetric");
  fmt::print("{:<17} {:<7} {:>14} {:>14} {:>16} {:>12} {:>12}\n", "precision", "scale", "buffer (texels)",
             "paper conv MiB", "allocated MiB", "allocated B", "paper prints");
  for (const auto& name : o.axes.precisions) {
    const LayerPrecision precision = layer_precision_from_string(name);
    // What every row of this precision states: frame, gather, texel, scale, extent, allocation.
    auto base_row = [&](int scale, const FlagBufferExtent& extent, std::uint64_t allocated) {
      return nlohmann::json{{"width_px", o.width_px},
                            {"height_px", o.height_px},
                            {"gather_n", o.size_n},
                            {"layers_full", layers},
                            {"aperture", o.aperture.name()},
                            {"precision", name},
                            {"bytes_per_texel", bytes_per_texel(precision)},
                            {"scale", scale},
                            {"extent", {{"width", extent.width}, {"height", extent.height}, {"layers", extent.layers}}},
                            {"allocated_bytes", allocated},
                            {"allocated_mib", allocated / kMiB}};
    };
    for (int scale : o.axes.scales.empty() ? find_method("flag").buffer_scales : o.axes.scales) {
      if (shape && scale != 1) continue;
      FlagBufferExtent extent = flag_buffer_extent(o.width_px, o.height_px, pattern, scale);
      double paper_bytes = flag_paper_bytes(o.width_px, o.height_px, pattern, precision, scale);
      if (shape) {
        extent.layers = layers;
        paper_bytes = static_cast<double>(extent.texels()) * bytes_per_texel(precision);
      }
      const auto allocated = vk::image_3d_requirement_bytes(ctx, layer_format(precision), extent.width,
                                                            extent.height, extent.layers);
      const double printed = paper_printed_mb(o, precision, scale);
      fmt::print("{:<17} 1/{:<5} {:>14} {:>14.2f} {:>16.2f} {:>12} {:>12}\n", name, scale,
                 fmt::format("{}x{}x{}", extent.width, extent.height, extent.layers), paper_bytes / kMiB,
                 allocated / kMiB, allocated, printed > 0 ? fmt::format("{} MB", printed) : "-");
      nlohmann::json row = base_row(scale, extent, allocated);
      row.update({{"layer_buffer", "full"},
                  {"paper_convention_bytes", paper_bytes},
                  {"paper_convention_mib", paper_bytes / kMiB},
                  {"texel_bytes", extent.texels() * bytes_per_texel(precision)}});
      if (printed > 0) row["paper_printed_mb"] = printed;
      if (shape) {  // beside the layers: the shape-weighted input and the chord tables (flag's gpu_memory)
        FilterOptions options = find_method("flag").defaults(pattern);
        options.precision = name;
        options.aperture = o.aperture;
        const MemoryUse use = find_method("flag").gpu_memory(options, o.width_px, o.height_px, &ctx);
        row["other_bytes"] = use.details["other_bytes"];
        row["method_bytes"] = use.bytes;
        fmt::print("{:<17} {:<7} plus {} B of shape-weighted input and chord tables: {} B ({:.2f} MiB) in all\n", "",
                   "", use.details["other_bytes"].get<std::uint64_t>(), use.bytes, use.bytes / kMiB);
      }
      rows.push_back(row);
    }
    // Streamed: a ring of B + 2 n k rows at full resolution, sized as the GPU driver sizes it.
    // The full buffer does not depend on k; the ring's rows do (n k): the pattern's own k.
    const GatherPattern grid = o.axes.patterns().front();
    for (int requested : shape ? std::vector<int>{} : o.band_rows) {
      const FlagStreamRing ring = flag_stream_ring(flag_buffer_extent(o.width_px, o.height_px, grid, 1),
                                                   grid.spacing_px, precision, requested, ctx.info().is_software());
      const FlagBufferExtent& e = ring.extent;
      const int band = ring.band_rows;
      const auto allocated = vk::image_3d_requirement_bytes(ctx, layer_format(precision), e.width, e.height, e.layers);
      const std::uint64_t texels = e.texels() * bytes_per_texel(precision);
      fmt::print("{:<17} {:<7} {:>14} {:>14} {:>16.2f} {:>12} {:>12}   band {} rows, k = {}, {} bands\n", name,
                 "stream", fmt::format("{}x{}x{}", e.width, e.height, e.layers), "-", allocated / kMiB, allocated,
                 "-", band, grid.spacing_px, (o.height_px + band - 1) / band);
      nlohmann::json row = base_row(1, e, allocated);
      row.update({{"spacing_px", grid.spacing_px},
                  {"layer_buffer", "streamed"},
                  {"band_rows", band},
                  {"band_rows_requested", requested},
                  {"texel_bytes", texels},
                  // The paper's convention has no fractional layers to drop here: the ring's texels.
                  {"paper_convention_bytes", texels},
                  {"paper_convention_mib", texels / kMiB}});
      rows.push_back(row);
    }
  }
  write_results(o.out_path, "bokehbench.memory", run_context(&ctx.info()),
                {{"convention",
                  "paper_convention_bytes = W*H*ceil(N/2)*bytes_per_texel/scale^3 (fractional layers, as the paper's "
                  "42 and 5.2 MB); allocated_bytes = vkGetImageMemoryRequirements of the whole-texel 3D image; "
                  "layer_buffer = streamed rows: a ring of band_rows + 2 n k rows (n = (N - 1) / 2, k = spacing_px)"},
                 {"buffers", rows}});
  fmt::print("wrote {}\n", o.out_path);
}

}  // namespace

void add_memory_command(CLI::App& app) {
  auto o = std::make_shared<MemoryOptions>();
  auto* cmd = app.add_subcommand("memory", "FLAG 3D-buffer size: paper convention and actual allocation");
  AxisFlags& a = o->axes;
  a.resolutions = {"1920x1080"};
  a.sizes = {"41x1"};  // the paper's 41x41 gather at full resolution: k = 1 (the ring's rows depend on k)
  a.precisions = {"f16", "f32"};  // scales: every one FLAG has
  a.add_to(cmd, {Axis::precisions, Axis::scales}, {Axis::resolutions, Axis::sizes, Axis::apertures});
  const Method& flag = find_method("flag");
  a.option(Axis::precisions)->check(CLI::IsMember(flag.precisions));
  a.option(Axis::scales)->check(CLI::IsMember(flag.buffer_scales));
  cmd->add_option("--band-rows", o->band_rows,
                  "Streamed layers: output rows per band, one row of the table per value (0: the device's auto)")
      ->check(CLI::Range(0, 1 << 16));
  cmd->add_option("--device", o->device, "Vulkan device index or name part");
  cmd->add_option("--out", o->out_path, "JSON output path");
  cmd->callback([o] { memory(*o); });
}

}  // namespace bokeh
