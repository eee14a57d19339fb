#pragma once
// The filter registry: each method is one CPU reference (kernels/) plus one GPU factory
// (bench/gpu/, shaders/). Adding a filter is one entry in filters.cpp.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "gpu/gpu_frame.hpp"
#include "image.hpp"
#include "lens.hpp"

namespace bokeh {

// Everything a CPU reference may read; the CoC pass has already run.
struct CpuFilterInput {
  const Image& color;      // 3ch linear
  const Image& depth_m;    // 1ch planar depth
  const Lens& lens;
  const Image& radius_px;  // 1ch, clamped to pattern.max_radius_px()
  const Image& packed;     // RGBA (rgb / discrete disc area, radius px)
  const gpu::FilterOptions& options;
  int threads;
};

struct FilterRegistration {
  std::string name;  // the --method value
  std::string description;
  std::vector<std::string> precisions;  // accepted FilterOptions::precision values, default first
  std::function<Image(const CpuFilterInput&)> cpu_reference;
  std::function<std::unique_ptr<gpu::GpuFilter>(gpu::GpuFrame&, const gpu::FilterOptions&)> make_gpu;
  // Input samples (taps) one output pixel costs, over all passes: the cost axis of Figure 9.
  std::function<double(const gpu::FilterOptions&)> samples_per_pixel;
  // Whether the gather pattern's N and k shape the result; false for fixed kernels that only take
  // the pattern's max radius (sweeps then skip grids that would repeat the same configuration).
  bool samples_pattern = true;
  std::vector<int> buffer_scales = {1};  // accepted FilterOptions::buffer_scale values
};

const std::vector<FilterRegistration>& registered_filters();
// Throws std::invalid_argument listing the valid names.
const FilterRegistration& find_filter(const std::string& name);
// Throws std::invalid_argument unless `filter` accepts the options' precision and buffer scale.
void check_options(const FilterRegistration& filter, const gpu::FilterOptions& options);

}  // namespace bokeh
