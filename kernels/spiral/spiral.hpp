#pragma once
// spiral: the single-pass scatter-as-gather bokeh of "Bokeh depth of field in a single pass" (2018 blog;
// Godot 4's circle mode is this shader). Each pixel walks a golden-angle spiral outwards from itself
// up to the largest CoC radius R. A sample at spiral radius r "contributes" as far as its own CoC
// reaches it: m = smoothstep(r - 1/2, r + 1/2, |sample CoC|). A sample behind the pixel (greater
// signed CoC) has its CoC clamped to clamp_factor x the pixel's own |CoC| first: the background may
// blur into a pixel only as far as that pixel is itself blurred. The blend is the blog's trick:
//   colour = centre, total = 1; per sample: colour += mix(colour / total, sample, m); total += 1;
//   result = colour / total,
// i.e. each contributing sample has the same weight and a non-contributing one adds the running
// average. Computed here in its running-average form (the same numbers, exactly the identity where no
// sample contributes):  avg += m (sample - avg) / (i + 2)  for the i-th sample (i from 0).
//
// Choices the blog leaves open, taken as Godot 4 does (bokeh_dof.glsl, MODE_BOKEH_CIRCULAR):
//   - the spiral: radius starts at the spacing s (the blog's RAD_SCALE, Godot's blur_scale), angle 0;
//     per sample angle += golden angle pi (3 - sqrt 5), radius += s / radius, while radius < R. So
//     radius^2 grows by ~2s per sample: a disc of radius R takes ~R^2 / (2s) samples;
//   - samples are bilinear fetches of colour and signed CoC (Godot reads a linearly filtered texture;
//     its alpha holds the signed blur size, near negative), and "behind" compares signed CoC (Godot)
//     rather than depth (blog): the same order, both grow with depth;
//   - the clamp factor 2 (Godot and the blog's "clamp(sample size, 0, center size * 2.0)").
// Not as Godot: a sample beyond the image's outermost pixel centres contributes nothing (the running
// average goes on) where Godot's clamp-to-edge sampler would repeat the border pixels, so light from
// outside the image is absent, as in the exact reference. Godot runs the circle at half resolution
// and composites by CoC; here it runs at full resolution (buffer scale 1 only).
//
// Energy: not conserved in general. At a constant CoC every pixel applies the same weights, so the
// filter is a normalised convolution and conserves energy away from the borders; where samples stop
// contributing (a blurred foreground over a sharp background) the running average weights a sample
// found after i others by 1 / (i + 2) rather than 1 / (samples + 1), so light near a blurred
// foreground object's centre is over-weighted (tests/kernels/spiral/test_spiral.cpp measures both).
#include <cstdint>
#include <vector>

#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// One spiral sample, as shaders/spiral/spiral.comp reads it (two vec4): its offset from the pixel
// split into whole pixels (exact small integers in float) and a fraction (split_offset), so every
// pixel uses the same bilinear weights.
struct SpiralSample {
  float x_px, y_px;        // whole-pixel part of the offset
  float fx, fy;            // fractional part, in [0, 1)
  float edge_start_px;     // spiral radius - 1/2: where the sample's smoothstep starts (exact in float)
  float inverse_count;     // 1 / (i + 2): the running average's weight of sample i
  float unused[2];
};

// The spiral for spacing s (px, > 0) up to radius R (px): empty if s >= R.
std::vector<SpiralSample> spiral_samples(double spacing_px, double max_radius_px);
// How many samples that is, without building it (~R^2 / (2s)).
std::int64_t spiral_sample_count(double spacing_px, double max_radius_px);

// signed_coc: RGBA from signed_coc_image (rgb, signed CoC radius px). Returns RGB.
Image spiral_blur(const Image& signed_coc, const std::vector<SpiralSample>& spiral, float clamp_factor,
                  int threads = default_cpu_threads());

}  // namespace bokeh
