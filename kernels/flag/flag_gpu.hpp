#pragma once
// FLAG on the GPU (flag_gpu.cpp): passes downsample (scale > 1), bracket (bracketed precisions),
// horizontal, vertical, upsample (scale > 1).
#include <cstdint>
#include <memory>

#include "flag.hpp"
#include "method.hpp"

namespace bokeh {

std::unique_ptr<gpu::GpuFilter> make_flag_gpu(gpu::GpuFrame& frame, const FilterOptions& options);

VkFormat layer_format(LayerPrecision precision);  // FLAG's 3D buffer format
// Bytes of the bracketed precisions' min/max buffer: 2 x rows x layers uvec4.
std::uint64_t flag_bracket_buffer_bytes(std::uint32_t rows, std::uint32_t layers);

}  // namespace bokeh
