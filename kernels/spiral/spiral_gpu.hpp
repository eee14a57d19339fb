#pragma once
#include <memory>
#include <vector>

#include "method.hpp"
#include "spiral.hpp"

namespace bokeh {

// Two passes: prepare (colour + signed CoC, shaders/common/signed_coc.comp) and spiral.
std::unique_ptr<gpu::GpuFilter> make_spiral_gpu(gpu::GpuFrame& frame, const std::vector<SpiralSample>& spiral,
                                                float clamp_factor);

}  // namespace bokeh
