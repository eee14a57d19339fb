#pragma once
// Circular separable convolution depth of field (Garcia, GDC 2018), CPU reference. A horizontal pass
// writes, per component, the complex response of every channel; a vertical pass convolves those with
// the same complex taps and combines them with the weights A, B. Image borders clamp to the edge, as
// Garcia's texture sampler does: light enters from beyond the border, unlike the exact reference's
// convention (exact_scatter.hpp), so within the largest CoC of the border the interior metrics are the
// fair measure (adaptive, fully_defocused, 800x600, 40 px: 23.0 dB whole, 30.7 dB interior).
#include <cstdint>
#include <string>
#include <vector>

#include "circular_coefficients.hpp"
#include <nlohmann/json.hpp>

#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// How the horizontal pass stores its complex intermediates (each real and imaginary part):
//   f32, f16: the value, rounded to half for f16 (Imath::half, as an RGBA16F target would).
//   bracketed10: Garcia's appendix. Per component and part, the 1D kernel G (Re F or Im F) becomes
//     G' = (G - O) / S with O = min tap, S = sum(G - O), so G' >= 0 and sums to 1; I' = sum J G' then
//     lies in [0, M] (M: per-channel max of the non-negative input, a per-dispatch constant like O, S)
//     and is stored as 10-bit unorm of I' / M. The box sum sum(J) over the same window goes to one
//     separate target (f16, of sum(J) / M); the vertical pass recovers I = S I' + O sum(J).
enum class IntermediatePrecision { f32, f16, bracketed10 };

// Garcia's bracketing of one real 1D kernel G: G' = (G - O) / S. The GPU uploads exactly these.
struct BracketedKernel {
  std::vector<float> taps;  // G', >= 0, sums to 1
  float offset = 0.0f;      // O = min G
  float scale = 0.0f;       // S = sum (G - O)
};
BracketedKernel bracket_kernel(const std::vector<float>& g);
const char* to_string(IntermediatePrecision precision);
IntermediatePrecision intermediate_precision_from_string(const std::string& name);  // throws on unknown names

// Fixed-kernel convolution of every channel of `image` (any channel count). bracketed10 throws
// std::invalid_argument on negative input values (the bracketed range assumes J >= 0) and brackets
// by the per-channel maxima M of the image, or by `channel_max` where given (one value per channel,
// each >= the image's own: the radius-following filter brackets every bucket of a field by the
// field's maxima, as the GPU reduces them once).
Image circular_convolve(const Image& image, const CircularKernel& kernel,
                        IntermediatePrecision precision = IntermediatePrecision::f32,
                        int threads = default_cpu_threads(), const std::vector<float>* channel_max = nullptr);

struct CircularFilterConfig {
  int near_components = 1;  // Garcia's production choice: 1 component near, 2 far
  int far_components = 2;
  int max_radius_px = 0;    // disc radius of both kernels (the CoC that gets the full blur)
  IntermediatePrecision precision = IntermediatePrecision::f32;
  bool adaptive = false;    // radius-following kernels (circular_blur_adaptive) instead of one fixed disc
};

// The radius-following filter's kernels ("adaptive"; Garcia's "precomputed filter weights for
// different radius ranges", GDC 2018): discs of radius disc_radius_px[k - 1] for buckets k = 1..K;
// bucket 0 is the identity (radius kIdentityRadiusPx: the exact scatter keeps a pixel of radius
// <= 0.5 px in place). The radii step from kMinBucketRadiusPx by kBucketRatio while that is less
// than kBucketSpacingPx, then by kBucketSpacingPx, stretched so the last is the max radius (29
// kernels at 40 px); more than kMaxBuckets widen the spacing (from a max radius of about 43 px).
// A pixel of radius r gets the bucket coordinate s = sum_k clamp(G (r - rho_(k-1)) /
// (rho_k - rho_(k-1)) - (G - 1) / 2, 0, 1) (rho_0 the identity radius, G = 1 / kBucketBlend):
// s = k - 1 + t between rho_(k-1) and rho_k, continuous, t = 0 below the middle kBucketBlend of the
// interval and 1 above it. Its light goes to buckets floor(s) and floor(s) + 1 with the hat weights
// max(0, 1 - |s - k|) (1 - t and t): the nearer kernel alone, except in that middle band, where the
// two mix so the blur grows continuously with the radius. Why not a few kernels far apart, mixed
// (Garcia's sketch): two discs 1.5x apart mixed half and half show as the smaller disc with a faint
// halo, not as a disc between them. Here every pixel's light keeps a disc within
// (1 + kBucketBlend) / 2 steps of its radius: within 0.9 px while the spacing is 1.5 px. A
// constant-trip loop, so the GPU evaluates it without divergent loads.
inline constexpr double kBucketRatio = 1.5;
inline constexpr double kBucketSpacingPx = 1.5;
inline constexpr double kBucketBlend = 0.2;
inline constexpr double kMinBucketRadiusPx = 1.0;
inline constexpr float kIdentityRadiusPx = 0.5f;
inline constexpr int kMaxBuckets = 31;  // bit k of a 32-bit mask per bucket, bit 0 the identity
struct CircularBuckets {
  std::vector<float> disc_radius_px;  // rho_1 .. rho_K, ascending; rho_K = the max radius
  std::vector<float> ramp_scale;      // G / (rho_k - rho_(k-1)), k = 1..K
  std::vector<float> ramp_offset;     // G rho_(k-1) / (rho_k - rho_(k-1)) + (G - 1) / 2
  int count() const { return static_cast<int>(disc_radius_px.size()); }
};
// Throws std::invalid_argument unless max_radius_px >= 1 (and finite).
CircularBuckets circular_buckets(double max_radius_px);
// s(r) above, in float, in the order the GPU evaluates it (k ascending).
float bucket_coordinate(const CircularBuckets& buckets, float radius_px);
// Layer alpha of a pixel outside a field: its hat weight is 0 for every bucket k >= 0.
inline constexpr float kNoBucket = -2.0f;

// Per-pixel CoC with fixed kernels (Garcia's near/far split). w = clamp(radius / max_radius, 0, 1);
// pixels nearer than focus form the near layer, farther ones the far layer, each stored as RGBA =
// (rgb w, w) and blurred at max_radius_px. Far: out = (1 - w) sharp + w rgb_b / a_b with the pixel's
// own w (background never spreads over sharper pixels; a_b <= 1e-4 keeps sharp). Near, composited
// last: alpha = clamp(a_b, 0, 1), out = (1 - alpha) out + rgb_b alpha / a_b, so the near field spreads
// over everything behind it; the blurred alpha does the edge bleeding Garcia gets from tiling max CoC.
Image circular_blur(const Image& color, const Image& radius_px, const Image& depth_m, double focus_distance_m,
                    const CircularFilterConfig& config, int threads = default_cpu_threads());

// Per-pixel CoC with radius-following kernels (config.adaptive). Each field (near, far; in focus:
// s = 0) becomes an RGBA layer (rgb, s), or (0, 0, 0, kNoBucket) for pixels outside it. For every
// bucket k >= 1 that some pixel of the field touches (hat > 0), the layer (rgb hat_k, hat_k) is
// convolved with bucket k's disc kernel (far_components far, near_components near) and summed in
// ascending k into the field's accumulator; the identity bucket adds (rgb hat_0, hat_0) at the pixel
// itself. So every pixel's light spreads over a disc of about its own CoC, with its coverage in alpha.
// Composite (Garcia's near/far split, over sums F far and N near):
//   behind = F.rgb / F.a for far pixels with F.a > 1e-4 (the mean colour of the far discs covering
//            it: the exact reference fills what nearer pixels hide with the view's mean), else the
//            sharp colour (in-focus pixels hide the far field behind them);
//   out    = (1 - N.a) behind + N.rgb where N.a < 1, else N.rgb / N.a: the near field spreads over
//            everything, linearly while it does not cover the pixel (its kernels' negative ringing
//            keeps its sign: a near light over black keeps its energy), normalised once it does.
//   For near pixels behind is F.rgb / max(F.a, 1 - N.a, 1e-4): the far discs reaching the pixel, as
//   much of them as the near field leaves visible (the exact reference's view, with nothing
//   invented where neither covers it).
// bracketed10 brackets every bucket of a field by the field's maxima (rgb max, alpha 1).
//
// Work skipped (exactly: the skipped values are 0). A bucket's response is 0 outside its pixels
// dilated by its kernel radius R. The CPU convolves each bucket over its pixels' bounding box
// dilated by R; the GPU visits kTilePx-square tiles (adaptive_tiles below): a bucket's horizontal
// pass computes the tiles whose row band holds a pixel of the bucket within ceil(R / kTilePx)
// tiles, and writes zeros in those the vertical pass reads besides; the vertical pass visits the
// tiles within ceil(R / kTilePx) tiles of a computed one along the column.
struct AdaptiveWork;
Image circular_blur_adaptive(const Image& color, const Image& radius_px, const Image& depth_m,
                             double focus_distance_m, const CircularFilterConfig& config,
                             int threads = default_cpu_threads(), AdaptiveWork* work = nullptr);

inline constexpr int kTilePx = 32;

// The tiles each bucket's GPU passes visit, per field (0 far, 1 near) and bucket k = 1..K ([k - 1]),
// as tiles.comp lists them, and what they cost.
struct AdaptiveWork {
  int tiles = 0;                              // of the frame (kTilePx squares, partial at the edges)
  std::uint32_t bucket_mask[2] = {0u, 0u};    // bit k: some pixel of the field touches bucket k
  std::vector<int> horizontal_tiles[2];       // convolved by bucket k's horizontal pass
  std::vector<int> zero_tiles[2];             // zeroed by it (read by the vertical pass)
  std::vector<int> vertical_tiles[2];         // convolved by its vertical pass
  double taps[2] = {0.0, 0.0};                // complex RGBA multiply-adds of both passes, all buckets
};
// From the radius-following layers (rgb, s) of both fields and each field's kernel tap radii.
AdaptiveWork adaptive_tiles(const Image& far_layer, const Image& near_layer, const CircularBuckets& buckets,
                            const std::vector<int> (&tap_radius_px)[2], const int (&components)[2]);

// What a radius-following frame ran, as the CPU reference and the GPU driver both report it
// (Method stats): bucket_radii_px (rho_1..rho_K), tiles, and per field (far_, near_):
// buckets_run, bucket_radii_px, horizontal_tiles, zero_tiles, vertical_tiles (per bucket run) and
// taps (what the passes multiply-add: the work model counts every bucket on every tile).
nlohmann::json bucket_stats(const CircularBuckets& buckets, const AdaptiveWork& work);

// How an error in the stored intermediates reaches a blurred channel: with every stored real
// (imaginary) part of component c off by at most err_re[c] (err_im[c]), the vertical pass's
// sum_j Hre (wr Fr + wi Fi) + Him (wi Fr - wr Fi) is off by at most the returned value.
double propagate_storage_error(const CircularKernel& k, const std::vector<double>& err_re,
                               const std::vector<double>& err_im);

// The largest error storing the intermediates as `precision` adds to a blurred channel, relative to
// the channel's maximum M over the layer: `units` roundings of each stored part (1: to nearest, as
// the CPU does; 2: either way, as Vulkan lets a GPU convert). f16: 2^-11 sum|G| M per part;
// bracketed10: S M / 1023 / 2 for the 10-bit code of I' / M, plus |O| (2R + 1) M 2^-11 for the f16
// box sum; f32: 0 (f32 arithmetic aside).
double circular_storage_bound(const CircularKernel& k, IntermediatePrecision precision, double units = 1);

// One circular_convolve of `channels` channels at kernel radius radius_px.
//   passes: horizontal + vertical (all components written at once, as MRTs on a GPU).
//   taps_per_pixel: complex multiply-adds per pixel and channel, both passes: 2 C (2R + 1).
//   intermediate_bytes_per_pixel: f32 C * 2 ch * 4; f16 C * 2 ch * 2; bracketed10: the 2 ch 10-bit
//     values of a component packed three to an A2B10G10R10 texel (4 ceil(2 ch / 3) B per component)
//     plus the shared box-sum target, RGBA16F (8 ceil(ch / 4) B): 8 C + 8 for RGB.
struct CircularCost {
  int passes;
  long taps_per_pixel;
  long intermediate_bytes_per_pixel;
};
CircularCost circular_cost(int components, int radius_px, IntermediatePrecision precision, int channels = 3);

}  // namespace bokeh
