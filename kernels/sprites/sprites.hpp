#pragma once
// sprites: contrast-detected bokeh sprites over a gather of the rest. de Rousiers & Pettineo, "Depth
// of Field with Bokeh Rendering" (OpenGL Insights ch. 15); Unreal's diaphragm DOF ships the same
// hybrid (its "hybrid scatter"). Where the chapter leaves a choice open, Unreal's choice is taken.
//
//   1. Detection: pixel p becomes a sprite when its CoC radius r >= min_radius_px (Unreal's
//      r.DOF.Scatter.MinCocRadius, default 3 px) and
//        L(colour(p)) - L(mean colour of its 8 neighbours, coordinates clamped to the image) > threshold,
//      L(c) = 0.299 R + 0.587 G + 0.114 B (the chapter's rule and weights). Sprites are appended in
//      any order; past max_sprites a pixel is counted as overflow and stays in the gather, so no
//      light is lost (Unreal drops it; we count, report and keep it).
//   2. Gather of the rest: the naive gather (kernels/naive) of the packed input with every sprite's
//      colour removed (Unreal also removes the scattered colour from its gather input). The chapter
//      leaves the blur open; the naive gather makes the method exactly naive + the scatter, so
//      their difference in time and error is the scatter's.
//   3. Sprites: a quad per sprite over pixels [p - f, p + f]^2, f = floor(r), drawn additively over
//      the gather. Its texture is the disc of radius r evaluated at each pixel centre with the
//      gathers' test, dx^2 + dy^2 <= r^2 for the integer offset (dx, dy) from p, and weight
//      1 / (the disc's pixel count): the disc's pixels sum to the source's colour (energy kept, as
//      the gathers keep it). A rasteriser covers a pixel when its centre lies inside the quad; the
//      quad's edges lie on pixel boundaries, so no centre lies on an edge and the tie-breaking rule
//      never applies: the GPU covers exactly the pixels this reference loops over.
//
// Any other aperture (issue 23): the sprite is the shape of circumradius r, a pixel at offset
// (dx, dy) lit when the aperture's gauge there is <= r, read from a table of every offset up to the
// pattern's largest radius (sprite_shape_lattice: naive's ShapeLattice at spacing 1, its floats
// uploaded as they are, so CPU and GPU test the same numbers), weight 1 / (the offsets the shape
// holds): the exact reference's shape, sampled at pixel centres as the gathers sample it. The shape
// lies inside its disc (ShapeLattice's guarantee), so inside the same quad. The gather of the rest is
// naive's shape gather, the sprites' colour taken out of its weighted input.
#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "aperture.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "naive_shape.hpp"
#include "parallel.hpp"

namespace bokeh {

struct SpriteSettings {
  float threshold = 1.0f;       // luminance above the neighbours' mean, linear units
  float min_radius_px = 3.0f;   // smaller circles of confusion stay in the gather
  int max_sprites = 65536;      // more are counted as overflow and stay in the gather
};

// Mirrors `Sprite` in shaders/sprites/sprite.glsl (std430).
struct Sprite {
  std::int32_t x_px = 0, y_px = 0;
  float radius_px = 0;
  float pixel_count = 0;             // pixels of its disc (or shape)
  float rgb_per_pixel[4] = {0, 0, 0, 0};  // colour / pixel_count
};
static_assert(sizeof(Sprite) == 32, "Sprite must match the shaders' std430 layout");

struct SpriteStats {
  std::int64_t detected = 0;     // pixels that passed the test
  std::int64_t drawn = 0;        // sprites appended and drawn: min(detected, max_sprites)
  std::int64_t overflowed = 0;   // detected - drawn: left in the gather
  std::int64_t quad_pixels = 0;  // pixels the drawn sprites' quads cover (fragments rasterised)
  int max_sprites = 0;
};
// The point's statistics as the GPU driver reports them too (GpuFilter::stats).
nlohmann::json to_json(const SpriteStats& stats);

// The table a non-disc sprite reads: the aperture's gauge at every integer offset within the pattern's
// largest radius M = n k (quads never reach further: radii are clamped to it). (2 M + 1)^2 floats,
// twice (as listed and sorted): kMaxShapeSpriteRadiusPx bounds M.
ShapeLattice sprite_shape_lattice(const Aperture& aperture, const GatherPattern& pattern);
constexpr int kMaxShapeSpriteRadiusPx = 256;  // 513^2 floats a table, 2 MiB for both

// L = 0.299 R + 0.587 G + 0.114 B, as the shader computes it.
float sprite_luminance(const float* rgb);
// Pixels of the disc of radius r: integer offsets (dx, dy) with dx^2 + dy^2 <= r^2.
int disc_pixel_count(float radius_px);

struct SpriteDetection {
  std::vector<Sprite> sprites;  // the first max_sprites detected, in row-major order of their pixels
  Image rest;                   // the packed input with the sprites' colour removed
  SpriteStats stats;
};
// color: 3+ channels; packed: RGBA (rgb / gather area, radius px) from pack_gather_input.
// shape: null for the disc, else sprite_shape_lattice's table (pixel_count: the offsets it holds).
SpriteDetection detect_sprites(const Image& color, const Image& packed, const SpriteSettings& settings,
                               const ShapeLattice* shape = nullptr);

// Adds each sprite's disc (or shape) to `image` (3+ channels), pixels outside the image dropped; at
// every pixel the sprites are added in list order.
void splat_sprites(Image& image, const std::vector<Sprite>& sprites, int threads = default_cpu_threads(),
                   const ShapeLattice* shape = nullptr);

// The method: detection, the naive gather of the rest (naive's shape gather for a non-disc aperture),
// the sprites added over it. Returns RGB.
Image sprite_bokeh(const Image& color, const Image& packed, const GatherPattern& pattern,
                   const SpriteSettings& settings, int threads = default_cpu_threads(), SpriteStats* stats = nullptr,
                   const Aperture& aperture = {});

}  // namespace bokeh
