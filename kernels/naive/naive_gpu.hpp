#pragma once
#include <memory>

#include "method.hpp"

namespace bokeh {

std::unique_ptr<gpu::GpuFilter> make_naive_gpu(gpu::GpuFrame& frame, const FilterOptions& options);

}  // namespace bokeh
