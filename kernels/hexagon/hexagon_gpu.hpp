#pragma once
#include <memory>

#include "hexagon.hpp"
#include "method.hpp"

namespace bokeh {

// Three passes: prepare (colour + signed CoC, shaders/common/signed_coc.comp), the two-output first
// pass and the three-rhombus second pass; `taps` is the largest CoC radius in whole pixels, and the
// blurs run along `directions` (the aperture's rotation).
std::unique_ptr<gpu::GpuFilter> make_hexagon_gpu(gpu::GpuFrame& frame, int taps, const HexagonDirections& directions);

}  // namespace bokeh
