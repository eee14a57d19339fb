// sprites: contrast-detected bokeh sprites drawn with an indirect draw over the naive gather of the
// rest (de Rousiers & Pettineo, OpenGL Insights ch. 15; Unreal's hybrid scatter). See sprites.hpp.
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "method.hpp"
#include "naive_gpu.hpp"
#include "sprites.hpp"
#include "sprites_gpu.hpp"
#include "vk/memory.hpp"

namespace bokeh::methods {

namespace {

// The method's options, parsed once per call into the settings sprite_bokeh and the GPU driver read
// (the gather of the rest reads its gather_block itself: naive_config).
SpriteSettings settings_of(const FilterOptions& o) {
  SpriteSettings s;
  s.threshold = static_cast<float>(o.number("sprite_threshold"));
  s.min_radius_px = static_cast<float>(o.number("sprite_min_radius"));
  s.max_sprites = o.integer("max_sprites");
  return s;
}

constexpr std::uint64_t kCounterBytes = sizeof(SpriteCounters);

}  // namespace

void declare_sprites(std::vector<Method>& methods) {
  Method m;
  m.name = "sprites";
  m.description = "bokeh sprites (de Rousiers & Pettineo, OpenGL Insights 15; Unreal's hybrid scatter): pixels "
                  "brighter than their neighbours are drawn as disc (or aperture shape) quads (indirect draw, additive) "
                  "over the naive gather of the rest";
  m.precisions = {"f32"};
  m.options = {
      {"sprite_threshold", "Sprites: luminance above the 8 neighbours' mean that makes a pixel a sprite (linear units)",
       1.0, 0.0, 1e6, false, {}, {1.0, 10.0}},
      {"sprite_min_radius", "Sprites: smallest CoC radius in px drawn as a sprite (Unreal's r.DOF.Scatter.MinCocRadius)",
       3.0, 0.0, 1e4, false},
      {"max_sprites", "Sprites: most sprites a frame draws; more are counted as overflow and left in the gather",
       65536, 0, 4194304, true},
      naive_gather_block_option(),  // the gather of the rest is naive's, with its GPU shape
  };
  m.device = [](const FilterOptions&) {
    vk::DeviceRequirements needs;
    needs.graphics_queue = true;  // the quads are drawn by a graphics pipeline on the compute queue
    needs.blend_attachment_formats = {kSpriteTargetFormat};
    return needs;
  };
  // Any aperture (issue 23): a non-disc sprite reads the shape's gauge table over the quad, and the
  // rest is naive's shape gather (sprites.hpp). The table covers every offset up to the pattern's
  // largest radius, which bounds it.
  m.aperture_unsupported = [](const FilterOptions& o) -> std::string {
    if (o.aperture.is_disc() || o.pattern.max_radius_px() <= kMaxShapeSpriteRadiusPx) return "";
    return fmt::format("sprites draws the aperture {} from a table of every pixel offset up to the pattern's largest "
                       "radius, kept to {} px; this pattern reaches {} px (the disc has no such limit)",
                       o.aperture.name(), kMaxShapeSpriteRadiusPx, o.pattern.max_radius_px());
  };
  m.cpu_reference = [](const CpuInput& in) {
    SpriteStats stats;
    Image out = sprite_bokeh(in.color, in.packed, in.options.pattern, settings_of(in.options), in.threads, &stats,
                             in.options.aperture);
    if (in.stats) *in.stats = to_json(stats);
    return out;
  };
  m.make_gpu = [](gpu::GpuFrame& frame, const FilterOptions& o) { return make_sprites_gpu(frame, o, settings_of(o)); };
  // The fragments the sprites rasterise depend on the scene: the point's stats carry them
  // (sprite_quad_pixels); the model counts what every frame does.
  m.work = [](const FilterOptions& o, int w, int h) {
    const double px = static_cast<double>(w) * h;
    std::vector<PassWork> work;
    // A shape: naive's weights first (colour and radius in, a binary search), which detection edits.
    if (!o.aperture.is_disc()) work.push_back({"shape_pack", px, px * 32, px * 16});
    work.push_back({"detect", px * 9, px * 32, kCounterBytes});                        // 3x3 colours, the radius
    work.push_back({"gather", px * o.pattern.samples_per_pixel(), px * 16, px * 16});  // naive's
    work.push_back({"sprites", 0, px * 32, px * 32});  // the gather into the target and back, plus the quads
    return work;
  };
  m.gpu_memory = [](const FilterOptions& o, int w, int h, vk::Context* ctx) {
    const std::uint64_t sprites = static_cast<std::uint64_t>(std::max(1, settings_of(o).max_sprites)) * sizeof(Sprite);
    std::uint64_t target = static_cast<std::uint64_t>(w) * h * 16;
    MemoryUse use;
    if (ctx) {
      target = vk::color_target_requirement_bytes(*ctx, kSpriteTargetFormat, w, h);
      use.from_driver = true;
    }
    use.bytes = sprites + target + kCounterBytes;
    use.details = {{"sprite_buffer_bytes", sprites}, {"color_target_bytes", target}, {"counter_bytes", kCounterBytes}};
    if (!o.aperture.is_disc()) {
      // The sprite shape's two tables of (2 M + 1)^2 floats, and naive's shape gather: its weighted
      // colour (vec4 a pixel) and two tables of N^2 floats.
      const auto side = static_cast<std::uint64_t>(2 * static_cast<int>(o.pattern.max_radius_px()) + 1);
      const auto n = static_cast<std::uint64_t>(o.pattern.size_n);
      const std::uint64_t shape = 2 * side * side * 4, gather = static_cast<std::uint64_t>(w) * h * 16 + 2 * n * n * 4;
      use.bytes += shape + gather;
      use.details["sprite_shape_bytes"] = shape;
      use.details["shape_gather_bytes"] = gather;
    }
    return use;
  };
  m.cpu_memory_bytes = [](const FilterOptions& o, int w, int h) {
    const auto px = static_cast<std::uint64_t>(w) * h;
    std::uint64_t bytes = px * 4 * sizeof(float) + std::min<std::uint64_t>(px, settings_of(o).max_sprites) * sizeof(Sprite);
    if (!o.aperture.is_disc()) {  // the rest's colour and radii, naive's weighted colour, the sprite tables
      const auto side = static_cast<std::uint64_t>(2 * static_cast<int>(o.pattern.max_radius_px()) + 1);
      bytes += px * (3 + 1 + 4) * sizeof(float) + 2 * side * side * sizeof(float);
    }
    return bytes;
  };
  // The same detection and sums as the CPU; the sprites land in another order (the atomic counter's),
  // and additive blending is exact up to rounding: a pixel covered by m sprites sums m + 1
  // non-negative terms, so two orders differ by at most 2 m 2^-24 of its value. m is at most the
  // sources whose disc reaches it: the largest radius's disc pixel count, or max_sprites (a shape
  // lies inside its disc, so the bound holds for every aperture). Plus naive's 1e-5 for the gather.
  m.gpu_tolerance = [](const FilterOptions& o) {
    const double overlap = std::min<double>(settings_of(o).max_sprites, disc_pixel_count(o.pattern.max_radius_px()));
    return 1e-5 + 2.0 * overlap * std::ldexp(1.0, -24);
  };
  m.storage_tolerance = [](const FilterOptions&) { return 0.0; };
  m.energy_note = "each sprite spreads its colour over its disc's pixels (weights 1 / their count) and the gather of "
                  "the rest uses naive's weights: both sum to the source's colour";
  methods.push_back(std::move(m));
}

}  // namespace bokeh::methods
