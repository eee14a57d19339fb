#pragma once
// The circular separable filters on the GPU (circular_gpu.cpp): passes layers, far_horizontal,
// far_vertical, near_horizontal, near_vertical.
#include <memory>

#include "circular_separable.hpp"
#include "method.hpp"

namespace bokeh {

// `components` (1..6) far-field components; the near field takes options' near_components. Disc
// radius: options.pattern.max_radius_px().
std::unique_ptr<gpu::GpuFilter> make_circular_gpu(gpu::GpuFrame& frame, const FilterOptions& options, int components);

// Bytes of one component's intermediate per pixel (RGBA layers), as the GPU stores it.
std::uint64_t circular_component_bytes_per_pixel(IntermediatePrecision precision);

}  // namespace bokeh
