#pragma once
#include <memory>

#include "method.hpp"

namespace bokeh {

// Three passes: prepare (colour + signed CoC, shaders/common/signed_coc.comp), the two-output first
// pass and the three-rhombus second pass; `taps` is the largest CoC radius in whole pixels.
std::unique_ptr<gpu::GpuFilter> make_hexagon_gpu(gpu::GpuFrame& frame, int taps);

}  // namespace bokeh
