#pragma once
// FLAG with a reduced-resolution 3D buffer (the paper's section 5: "Half resolution or quarter
// resolution 3D buffers could be used"), at 1/s (s = 2 half, 4 quarter), in four passes. The GPU
// version (kernels/flag/flag_gpu.cpp, shaders/flag/downsample.comp, upsample.comp) mirrors this
// pass for pass, in the same float arithmetic.
//
// Pattern. The full-res pattern has L = ceil(N/2) layers at spacing k. The low-res one has
// L' = ceil(L / s) layers, N' = 2 L' - 1, at the same k in low-res pixels (s k full-res pixels), so its
// largest circle, k (N' - 1) / 2 low-res px = s k (L' - 1) full-res px, stays ~ k (N - 1) / 2
// (exactly for 1080p's 41 at s = 2 and 4; 21 at s = 4 reaches 16 of 20 px). The buffer is
// ceil(W/s) x ceil(H/s) x L' texels, as flag_buffer_extent() counts it.
//
// Split by CoC. A low-res buffer cannot represent circles smaller than about s full-res px: a
// source of radius r goes to the low-res buffer with weight w(r) = clamp(2 r / s - 1, 0, 1) (0 up
// to r = s/2, 1 from r = s) and stays at full resolution, as a sharp pixel, with weight 1 - w(r).
//
//  1. downsample (low-res grid): per s x s block (clipped at the right and bottom edges, n pixels):
//       colour' = sum_i w_i c_i / n                   (energy: each block carries its large-CoC light)
//       radius' = (sum_i w_i r_i / sum_i w_i) / s     (0 if sum_i w_i = 0), clamped to k (N' - 1) / 2
//     i.e. the w-weighted MEAN radius, not the max. Mean is unbiased where depth varies smoothly
//     (most of a frame): max would grow every circle by up to s/2 times the CoC slope and push edge
//     colours further out. The case that argues for max, a block straddling a focus edge, is taken
//     care of by w: the sharp pixels of the block have w = 0 and neither dim nor shrink the radius.
//     Packed as FLAG's input: (colour' / discrete disc area of radius' in the low-res pattern, radius').
//  2-3. FLAG horizontal + vertical on the low-res packed image (any LayerPrecision) -> B (low res).
//  4. upsample (full-res grid): out(p) = (1 - w(r_p)) c_p + bilinear(B at ((x + 0.5)/s - 0.5,
//     (y + 0.5)/s - 0.5), edges clamped).
//     Additive, not a blend: FLAG's output is a sum over sources, and B already holds every
//     large-CoC source's share (including the background discs that spill over a sharp pixel, as
//     full-res FLAG has them); the sharp part of pixel p adds its own colour. With all radii below
//     s/2 the output is the input exactly (B = 0); with all radii >= s it is the upsampled B.
//     Bilinear rather than a depth/CoC bilateral upsample: FLAG has no occlusion, so B is a sum of
//     disc indicators with no edges at depth or CoC discontinuities to preserve; a CoC-similarity
//     weight (1 / (1 + ((s r'_t - r_p) / s)^2) on the four taps) measured no better against full-res
//     f32 FLAG on hoops, pillars and points at 480x270, N = 21/41, s = 2/4 (RMSE within -5% .. +1%),
//     and a (1 - w) c + w B blend was 2-14% worse. The CoC similarity enters where it matters, in w.
#include <vector>

#include "flag.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"

namespace bokeh {

// The resolution divisors of FLAG's 3D buffer: 1 full, 2 half, 4 quarter (the method's
// Method::buffer_scales; flag_memory.hpp sizes the same buffers).
const std::vector<int>& flag_buffer_scales();
// Throws std::invalid_argument unless `scale` is one of flag_buffer_scales().
void check_buffer_scale(int scale);

// The low-res pattern at 1/scale: N' = 2 ceil(ceil(N/2) / scale) - 1, same k. scale 1 gives `full`.
GatherPattern reduced_pattern(const GatherPattern& full, int scale);

// w(r) above: the share of a source of radius r (full-res px) that the low-res buffer carries.
inline float low_res_weight(float radius_px, int scale) {
  const float w = radius_px * (2.0f / static_cast<float>(scale)) - 1.0f;
  return w < 0.0f ? 0.0f : (w > 1.0f ? 1.0f : w);
}

// Pass 1: colour (3+ channels, linear, full res) and radius (1 channel, full-res px) -> low-res packed RGBA.
Image flag_downsample(const Image& color, const Image& radius_px, const GatherPattern& low_pattern, int scale);
// Pass 4: the low-res FLAG output (RGB) back to full resolution.
Image flag_upsample(const Image& blurred_low, const Image& color, const Image& radius_px, int scale);

struct ReducedFlag {
  GatherPattern pattern;  // the low-res pattern
  Image packed;           // low-res (rgb / area', radius')
  FlagLayers layers;      // low-res 3D buffer as the vertical pass reads it
  Image blurred;          // low-res FLAG output, RGB
  Image output;           // full-res output, RGB
};

// The whole pipeline with its intermediates. scale 1 is plain FLAG (packed with pack_gather_input,
// output = blurred). Throws for scales not in flag_buffer_scales() and, for unsigned precisions, negative colours.
ReducedFlag flag_reduced(const Image& color, const Image& radius_px, const GatherPattern& pattern, int scale,
                         LayerPrecision precision, int threads = default_cpu_threads());
Image flag_reduced_blur(const Image& color, const Image& radius_px, const GatherPattern& pattern, int scale,
                        LayerPrecision precision, int threads = default_cpu_threads());

}  // namespace bokeh
