#pragma once
// Naive quadratic gather (FLAG paper section 3.1): every pixel visits all N x N pattern samples.
#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// packed: RGBA = (rgb / discrete disc area, radius px), from pack_gather_input. Returns RGB.
// Vectorised across eight adjacent pixels; each pixel adds its samples in the order of
// naive_gather_reference, so both give the same image bit for bit (tests/methods/test_gather.cpp).
Image naive_gather(const Image& packed, const GatherPattern& pattern, int threads = default_cpu_threads());

// The straightforward loop, one pixel at a time, rows then columns of the pattern: the definition
// naive_gather is tested against.
Image naive_gather_reference(const Image& packed, const GatherPattern& pattern, int threads = default_cpu_threads());

}  // namespace bokeh
