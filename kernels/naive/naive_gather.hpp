#pragma once
// Naive quadratic gather (FLAG paper section 3.1): every pixel visits all N x N pattern samples.
#include "coc_tiles.hpp"
#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// packed: RGBA = (rgb / discrete disc area, radius px), from pack_gather_input. Returns RGB.
// Vectorised across eight adjacent pixels; each pixel adds its samples in the order of
// naive_gather_reference, so both give the same image bit for bit (tests/kernels/flag/test_flag_cpu.cpp).
// tiles (adaptive mode): the tile-max CoC map of `packed` (coc_tiles.hpp); each eight pixels then
// visit only the samples inside the largest disc D of their tiles, which holds every sample that adds
// anything to them: the same image, bit for bit.
Image naive_gather(const Image& packed, const GatherPattern& pattern, int threads = default_cpu_threads(),
                   const CocTiles* tiles = nullptr);

// The straightforward loop, one pixel at a time, rows then columns of the pattern: the definition
// naive_gather is tested against.
Image naive_gather_reference(const Image& packed, const GatherPattern& pattern, int threads = default_cpu_threads());

}  // namespace bokeh
