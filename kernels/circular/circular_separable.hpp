#pragma once
// Circular separable convolution depth of field (Garcia, GDC 2018), CPU reference. A horizontal pass
// writes, per component, the complex response of every channel; a vertical pass convolves those with
// the same complex taps and combines them with the weights A, B. Image borders clamp to the edge.
#include <string>
#include <vector>

#include "circular_coefficients.hpp"
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
// std::invalid_argument on negative input values (the bracketed range assumes J >= 0).
Image circular_convolve(const Image& image, const CircularKernel& kernel,
                        IntermediatePrecision precision = IntermediatePrecision::f32,
                        int threads = default_cpu_threads());

struct CircularFilterConfig {
  int near_components = 1;  // Garcia's production choice: 1 component near, 2 far
  int far_components = 2;
  int max_radius_px = 0;    // disc radius of both kernels (the CoC that gets the full blur)
  IntermediatePrecision precision = IntermediatePrecision::f32;
};

// Per-pixel CoC with fixed kernels (Garcia's near/far split). w = clamp(radius / max_radius, 0, 1);
// pixels nearer than focus form the near layer, farther ones the far layer, each stored as RGBA =
// (rgb w, w) and blurred at max_radius_px. Far: out = (1 - w) sharp + w rgb_b / a_b with the pixel's
// own w (background never spreads over sharper pixels; a_b <= 1e-4 keeps sharp). Near, composited
// last: alpha = clamp(a_b, 0, 1), out = (1 - alpha) out + rgb_b alpha / a_b, so the near field spreads
// over everything behind it; the blurred alpha does the edge bleeding Garcia gets from tiling max CoC.
Image circular_blur(const Image& color, const Image& radius_px, const Image& depth_m, double focus_distance_m,
                    const CircularFilterConfig& config, int threads = default_cpu_threads());

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
