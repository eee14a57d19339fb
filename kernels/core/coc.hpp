#pragma once
// Circle-of-confusion pass: depth -> radius (px), then the packed input every gather method reads.
#include "gather_pattern.hpp"
#include "image.hpp"
#include "lens.hpp"
#include "parallel.hpp"

namespace bokeh {

// Throws std::invalid_argument naming the first pixel (and channel) whose value is NaN or infinite:
// a non-finite colour would spread over its whole disc (or, through a separable kernel, the whole
// frame) without a word. Finite values of any size pass (see Method::input_limit for saturation).
void check_color(const Image& color);
// Throws std::invalid_argument unless depth has one channel and every value is finite and > 0 metres
// (naming the pixel). Infinity is refused rather than taken as the limit: |D - P| / D is NaN there.
void check_depth(const Image& depth_m);

// Per-pixel CoC radius in pixels from planar depth (metres), clamped to [0, max_radius_px].
// Throws if a depth is not finite and positive (naming the pixel).
Image coc_radius_image(const Image& depth_m, const Lens& lens, float max_radius_px);

// The paper packs colour and radius in one RGBA texel. We pack (rgb / discrete disc area, radius):
// gathers then only test the disc and add. RGB of `color` is linear. Rows split over `threads`.
Image pack_gather_input(const Image& color, const Image& radius_px, const GatherPattern& pattern,
                        int threads = default_cpu_threads());

// The largest |D - P| / D in a depth map: the CoC scale that reaches a given radius is r / this.
double max_defocus_ratio(const Image& depth_m, const Lens& lens);

// The lens with its f-stop set so that the scene's largest CoC radius equals radius_px: how a sweep
// gives every gather size a scene whose circles spread over [0, max radius]. radius_px 0 (or a scene
// whose depths all lie at the focus distance) gives a pinhole (f/1e9); a negative, NaN or infinite
// radius throws std::invalid_argument.
Lens with_max_coc_radius(Lens lens, const Image& depth_m, double radius_px);

}  // namespace bokeh
