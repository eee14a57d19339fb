#pragma once
// Naive quadratic gather (FLAG paper section 3.1): every pixel visits all N x N pattern samples.
#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// packed: RGBA = (rgb / discrete disc area, radius px), from pack_gather_input. Returns RGB.
Image naive_gather(const Image& packed, const GatherPattern& pattern, int threads = default_cpu_threads());

}  // namespace bokeh
