#pragma once
// Circle-of-confusion pass: depth -> radius (px), then the packed input every gather method reads.
#include "gather_pattern.hpp"
#include "image.hpp"
#include "lens.hpp"
#include "parallel.hpp"

namespace bokeh {

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
// gives every gather size a scene whose circles spread over [0, max radius].
Lens with_max_coc_radius(Lens lens, const Image& depth_m, double radius_px);

}  // namespace bokeh
