#pragma once
// Size of FLAG's 3D buffer: in the paper's convention and as whole texels.
#include <cstdint>

#include "flag.hpp"
#include "gather_pattern.hpp"

namespace bokeh {

struct FlagBufferExtent {
  int width = 0, height = 0, layers = 0;
  std::uint64_t texels() const { return static_cast<std::uint64_t>(width) * height * layers; }
};

// The buffer at 1/scale resolution (scale 1 full, 2 half, 4 quarter): X, Y and the layer count
// are all divided, rounded up to whole texels and layers.
FlagBufferExtent flag_buffer_extent(int width_px, int height_px, const GatherPattern& pattern, int scale);

// The paper's convention (section 3.2.4 and 5): W * H * ceil(N/2) * bytes per texel / scale^3, i.e.
// fractional layers. This is what gives 332 MB (1080p, 41x41, RGBA16F) and then /8 = 42 MB, /64 = 5.2 MB.
// The paper's "MB" are MiB: 348,364,800 B = 332.2 MiB. Every LayerPrecision, through bytes_per_texel:
// f32 16 B, f16 8, r11g11b10f 4, unorm10_bracketed 4, unorm16_bracketed 8 (the bracketed ones' offsets
// and scales, 2 x rows x layers x 16 B on the GPU, are not part of the 3D buffer).
double flag_paper_bytes(int width_px, int height_px, const GatherPattern& pattern, LayerPrecision precision, int scale);

// Whole texels at the format's size, before any driver padding.
std::uint64_t flag_texel_bytes(int width_px, int height_px, const GatherPattern& pattern, LayerPrecision precision,
                               int scale);

constexpr double kMiB = 1024.0 * 1024.0;

}  // namespace bokeh
