#pragma once
// GPU implementations, one factory each; bench/filters.cpp registers them.
#include <memory>

#include "gpu_frame.hpp"

namespace bokeh::gpu {

std::unique_ptr<GpuFilter> make_naive_gpu(GpuFrame& frame, const FilterOptions& options);
std::unique_ptr<GpuFilter> make_flag_gpu(GpuFrame& frame, const FilterOptions& options);
// Circular separable filter with `components` (1..6) far-field components; the near field uses
// options.near_components when > 0, else the same count. Disc radius: options.pattern.max_radius_px().
std::unique_ptr<GpuFilter> make_circular_gpu(GpuFrame& frame, const FilterOptions& options, int components);

VkFormat layer_format(LayerPrecision precision);  // FLAG's 3D buffer format
// Bytes of the bracketed precisions' min/max buffer: 2 x rows x layers uvec4 (flag_gpu.cpp).
std::uint64_t flag_bracket_buffer_bytes(std::uint32_t rows, std::uint32_t layers);

}  // namespace bokeh::gpu
