#pragma once
// FLAG (FLAG paper section 3.2): a horizontal pass writing a 3D buffer of per-layer cumulative row
// contributions, then a vertical pass summing layer |dy| of each row. Linear in N per pixel.
//
// Vertical symmetry (paper 3.2.2: "If the blur shape has vertical symmetry, the memory requirements
// can be halved"): this layout already takes that halving. A disc is symmetric about its row, so the
// contribution of row Y to the pixel dy rows above equals its contribution dy rows below; the buffer
// stores one layer per |dy| = z k, ceil(N/2) = (N + 1) / 2 layers instead of N, and the vertical pass
// reads layer |j| for both row y + j k and row y - j k. There is nothing further to halve for discs.
#include <cstdint>
#include <string>
#include <vector>

#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// How the 3D buffer stores its layers. The CPU reference rounds each stored value the way the
// GPU's image format does, so precision effects can be checked on the CPU:
//   f32                RGBA32F, 16 B/texel: exact.
//   f16                RGBA16F, 8 B (the paper's): round to nearest even, 11 significant bits
//                      (relative error <= 2^-11; a driver rounding toward zero gives up to 2^-10).
//   r11g11b10f         B10G11R11_UFLOAT_PACK32, 4 B: unsigned floats with 5 exponent bits (bias 15)
//                      and 6 (R, G) / 5 (B) mantissa bits, emulated exactly with round to nearest even
//                      (relative error <= 2^-7 R/G, 2^-6 B; toward zero: 2^-6, 2^-5). No sign bit.
//   unorm10_bracketed  A2B10G10R10_UNORM_PACK32, 4 B: RGB as 10-bit codes of (v - offset) / scale,
//   unorm16_bracketed  R16G16B16A16_UNORM, 8 B: 16-bit codes of the same; alpha unused.
// Bracketing (Garcia 2018, appendix; here applied to FLAG's layers): offset and scale are kept per
// row, layer and channel: offset = the smallest value of that layer along the row, scale = largest -
// smallest, both of the f32 values the horizontal pass computes. The stored code is
// round((v - offset) / scale * (2^b - 1)) and the vertical pass reads offset + scale * code / (2^b - 1):
// absolute error <= scale / (2^b - 1) / 2 (one code, scale / (2^b - 1), for a driver that may pick
// either neighbour, as Vulkan allows). A layer that is constant along its row (scale 0) is exact.
// Layer values are cumulative sums of colour / area, so they are >= 0 exactly when colours are:
// the unsigned precisions (r11g11b10f and both bracketed) reject negative colours with an error.
enum class LayerPrecision { f32, f16, r11g11b10f, unorm10_bracketed, unorm16_bracketed };
const char* to_string(LayerPrecision precision);
LayerPrecision layer_precision_from_string(const std::string& name);  // throws on unknown names
const std::vector<LayerPrecision>& all_layer_precisions();           // in the order above
int bytes_per_texel(LayerPrecision precision);  // RGBA texel as the GPU stores it
bool is_bracketed(LayerPrecision precision);
bool is_unsigned(LayerPrecision precision);  // r11g11b10f and the bracketed ones: no negative values
int bracket_levels(LayerPrecision precision);  // 2^b - 1 of a bracketed precision (1023, 65535), else 0

// One stored value through a per-value format (f32, f16, r11g11b10f) as the CPU emulation rounds it;
// `channel` 0..2 (r11g11b10f has a 5-bit mantissa in blue). Throws for bracketed precisions.
float round_layer_value(float value, LayerPrecision precision, int channel);
// An unsigned float with 5 exponent bits (bias 15, subnormals) and `mantissa_bits`, round to nearest
// even; <= 0 and NaN give 0, values over the largest finite one clamp to it.
float round_to_ufloat(float value, int mantissa_bits);
// A bracketed value as the vertical pass reads it back: offset + scale * round((v - offset) / scale * L) / L.
float bracket_round_trip(float value, float offset, float scale, int levels);

struct FlagLayers {
  int width = 0, height = 0, layers = 0;
  std::vector<float> rgb;  // [(layer * height + y) * width + x] * 3, as the vertical pass reads them
  // Bracketed precisions only: per row, layer and channel, [(y * layers + z) * 3 + c].
  std::vector<float> bracket_offset, bracket_scale;
  float* at(int x, int y, int z) { return rgb.data() + ((static_cast<std::size_t>(z) * height + y) * width + x) * 3; }
  const float* at(int x, int y, int z) const {
    return rgb.data() + ((static_cast<std::size_t>(z) * height + y) * width + x) * 3;
  }
  std::size_t bracket_index(int y, int z, int c) const { return (static_cast<std::size_t>(y) * layers + z) * 3 + c; }
};

// Throws std::invalid_argument naming the first pixel with a negative (or NaN) colour channel if
// `precision` cannot store negative values. packed: RGBA (rgb / area, radius) or plain RGB.
void check_layer_input(const Image& packed, LayerPrecision precision);

FlagLayers flag_horizontal(const Image& packed, const GatherPattern& pattern, LayerPrecision precision,
                           int threads = default_cpu_threads());
// Output columns per row segment of the GPU horizontal pass's scan binning (horizontal_bins = scan,
// shaders/flag/horizontal_scan.comp): each segment also reads the n samples either side of it, so
// larger segments waste fewer loads: at N = 41 and 81 (800x600, k = 2) 256 columns took 0.81 and 0.75
// of 64 columns' time, and 512 (a whole row of one phase at 800 px, k = 2: no halo) 0.976 [0.963,
// 0.991] and 0.927 [0.918, 0.942] of 256's FLAG frame at N = 81 and 153 (`bokehbench ab`, alone;
// results/roofline/scan_segment_512_ab.json). The difference array is SEGMENT vec3 per invocation
// whatever N; the tests check the pass against its CPU mirror bit for bit across segments and at the
// largest pattern (lavapipe computed wrong layers past ~324 vec3 of the bins' arrays, flag_gpu.cpp).
constexpr int kFlagScanSegment = 512;
// flag_horizontal's layers summed in the GPU scan binning's order, bit for bit (f32; the other
// per-value precisions round the same f32 values): per row, lattice phase, segment of `segment`
// columns at stride k and layer z, each sample whose disc reaches z adds itself at the start of its
// interval of columns (clamped to the segment) and subtracts itself past its end, in a difference
// array, in row order; a prefix sum along the segment gives the layer. The same samples per layer as
// flag_horizontal, in another order. Throws std::invalid_argument for bracketed precisions.
FlagLayers flag_horizontal_scan(const Image& packed, const GatherPattern& pattern, LayerPrecision precision,
                                int segment = kFlagScanSegment, int threads = default_cpu_threads());
// Per pixel, rows y + j k, j = -n .. n: layer |j| (one half: the disc, mirror-symmetric shapes) or, with
// both_halves (shapes that are not mirror-symmetric, kernels/flag/flag_shape.hpp), layer n - j.
Image flag_vertical(const FlagLayers& layers, const GatherPattern& pattern, int threads = default_cpu_threads(),
                    bool both_halves = false);
// The whole FLAG blur. For the per-value precisions (f32, f16, r11g11b10f) it runs strip by strip with
// both passes fused, so no layer leaves a strip's scratch (a few hundred KiB a thread), vectorised, bit
// for bit flag_blur_reference's result (tested); the bracketed precisions take flag_blur_reference
// (their brackets span whole rows).
Image flag_blur(const Image& packed, const GatherPattern& pattern, LayerPrecision precision = LayerPrecision::f32,
                int threads = default_cpu_threads());
// Bytes flag_blur allocates beyond its input and output for the per-value precisions: the disc
// indices (4 B a pixel) and each thread's strip scratch.
std::uint64_t flag_blur_cpu_bytes(int width_px, int height_px, const GatherPattern& pattern, int threads);
// flag_vertical(flag_horizontal(...)): the straightforward passes through the whole 3D buffer.
Image flag_blur_reference(const Image& packed, const GatherPattern& pattern, LayerPrecision precision,
                          int threads = default_cpu_threads());

// flag_blur streamed through a ring of rows, as the GPU's layer_buffer = streamed runs it
// (kernels/flag/flag_gpu.hpp): bands of `band_rows` output rows; for each, the horizontal pass fills
// the ring (B + 2 n k rows, at most the height) up to the band's last row + n k, then the vertical
// pass sums the band. Bit for bit flag_blur's result for the per-value precisions (the same per-pixel
// operations); throws std::invalid_argument for bracketed ones and for band_rows < 1. The method's
// CPU reference for layer_buffer = streamed.
Image flag_blur_streamed(const Image& packed, const GatherPattern& pattern, LayerPrecision precision, int band_rows,
                         int threads = default_cpu_threads());
// Bytes flag_blur_streamed allocates beyond its input and output: the ring (f32, rows padded to whole
// vectors) and each thread's scratch.
std::uint64_t flag_streamed_cpu_bytes(int width_px, int height_px, const GatherPattern& pattern, int band_rows,
                                      int threads);

}  // namespace bokeh
