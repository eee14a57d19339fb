#pragma once
// gaussian: the speed floor engines used before bokeh. The whole image is blurred by one separable
// Gaussian whose 2-sigma radius is the scene's largest CoC R (sigma = R / 2, taps -R..R, normalised,
// edges clamped), then each pixel mixes sharp and blurred by w = clamp(r / R, 0, 1). The clamped edges
// bring light in from beyond the border, unlike the exact reference (exact_scatter.hpp): within R of
// the border the interior metrics are the fair measure.
#include <vector>

#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// The 2R + 1 normalised taps for sigma = R / 2 (R >= 1).
std::vector<float> gaussian_taps(int radius_px);

// color: 3+ channels; radius_px: 1 channel. Returns RGB.
Image gaussian_blur(const Image& color, const Image& radius_px, int max_radius_px, int threads = default_cpu_threads());

}  // namespace bokeh
