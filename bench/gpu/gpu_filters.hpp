#pragma once
// GPU implementations, one factory each; bench/filters.cpp registers them.
#include <memory>

#include "gpu_frame.hpp"

namespace bokeh::gpu {

std::unique_ptr<GpuFilter> make_naive_gpu(GpuFrame& frame, const FilterOptions& options);
std::unique_ptr<GpuFilter> make_flag_gpu(GpuFrame& frame, const FilterOptions& options);

VkFormat layer_format(LayerPrecision precision);  // FLAG's 3D buffer format

}  // namespace bokeh::gpu
