#include "filters.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <string>

#include "circular_separable.hpp"
#include "flag.hpp"
#include "flag_reduced.hpp"
#include "gpu/gpu_filters.hpp"
#include "naive_gather.hpp"

namespace bokeh {

namespace {

// circularN: Garcia's circular separable filter with N far-field components. The near field uses
// FilterOptions::near_components if > 0, else N as well; Garcia's production choice (Frostbite) is
// `--method circular2 --near-components 1`. Both kernels blur a disc of radius k (N - 1) / 2, the
// gather pattern's max radius: the circular filters take their (fixed) kernel radius from the same
// gather-size axis as naive and FLAG, so a figure9 sweep compares them at the same largest CoC, and
// the per-pixel CoC enters only through the near/far alpha w = radius / max radius.
FilterRegistration circular_registration(int components) {
  return {"circular" + std::to_string(components),
          std::to_string(components) +
              "-component circular separable convolution (Garcia 2018): complex-Gaussian horizontal + vertical "
              "passes on near/far layers, fixed disc of radius k(N-1)/2 (near components: --near-components)",
          {"f32", "f16", "bracketed10"},
          [components](const CpuFilterInput& in) {
            CircularFilterConfig config;
            config.far_components = components;
            config.near_components = in.options.near_components > 0 ? in.options.near_components : components;
            config.max_radius_px = static_cast<int>(in.options.pattern.max_radius_px());
            config.precision = intermediate_precision_from_string(in.options.precision);
            return circular_blur(in.color, in.radius_px, in.depth_m, in.lens.focus_distance_m, config, in.threads);
          },
          [components](gpu::GpuFrame& frame, const gpu::FilterOptions& options) {
            return gpu::make_circular_gpu(frame, options, components);
          },
          // Near and far layers, each a horizontal and a vertical pass over C complex taps of the kernel
          // whose disc edge (u = 1.1) falls on the max radius: tap radius ceil(s * radius / 1.1).
          [components](const gpu::FilterOptions& o) {
            const double disc_px = std::max(1.0f, o.pattern.max_radius_px());
            const int near = o.near_components > 0 ? o.near_components : components;
            long taps = 0;
            for (int c : {components, near}) {
              const int tap_radius = make_circular_kernel_for_disc(c, disc_px).radius_px;
              taps += circular_cost(c, tap_radius, IntermediatePrecision::f32).taps_per_pixel;
            }
            return static_cast<double>(taps);
          },
          /*samples_pattern=*/false};
}

}  // namespace

const std::vector<FilterRegistration>& registered_filters() {
  static const std::vector<FilterRegistration> filters = [] {
    std::vector<FilterRegistration> all = {
        {"naive", "naive quadratic gather, N x N samples at spacing k (FLAG paper 3.1)", {"f32"},
         [](const CpuFilterInput& in) { return naive_gather(in.packed, in.options.pattern, in.threads); },
         gpu::make_naive_gpu,
         [](const gpu::FilterOptions& o) { return static_cast<double>(o.pattern.samples_per_pixel()); }},
        {"flag", "FLAG: horizontal pass into a ceil(N/2)-layer 3D buffer, vertical pass (FLAG paper 3.2)",
         {"f16", "f32", "r11g11b10f", "unorm10_bracketed", "unorm16_bracketed"},
         [](const CpuFilterInput& in) {
           // FilterOptions::buffer_scale > 1: the reduced-resolution pipeline of kernels/flag_reduced.hpp.
           const LayerPrecision precision = layer_precision_from_string(in.options.precision);
           if (in.options.buffer_scale != 1)
             return flag_reduced_blur(in.color, in.radius_px, in.options.pattern, in.options.buffer_scale, precision,
                                      in.threads);
           return flag_blur(in.packed, in.options.pattern, precision, in.threads);
         },
         gpu::make_flag_gpu,
         // N row samples + N layer reads, at 1/s resolution with the reduced pattern: per full-res pixel.
         [](const gpu::FilterOptions& o) {
           const GatherPattern p = reduced_pattern(o.pattern, o.buffer_scale);
           return 2.0 * p.size_n / (o.buffer_scale * o.buffer_scale);
         },
         /*samples_pattern=*/true, /*buffer_scales=*/{1, 2, 4}},
    };
    for (int n = 1; n <= kMaxCircularComponents; ++n) all.push_back(circular_registration(n));
    return all;
  }();
  return filters;
}

const FilterRegistration& find_filter(const std::string& name) {
  std::string known;
  for (const auto& f : registered_filters()) {
    if (f.name == name) return f;
    known += (known.empty() ? "" : ", ") + f.name;
  }
  throw std::invalid_argument("unknown method '" + name + "' (known: " + known + ")");
}

void check_options(const FilterRegistration& filter, const gpu::FilterOptions& options) {
  const auto& precisions = filter.precisions;
  if (std::find(precisions.begin(), precisions.end(), options.precision) == precisions.end())
    throw std::invalid_argument(fmt::format("method '{}' does not store intermediates as '{}' (it accepts: {})",
                                            filter.name, options.precision, fmt::join(precisions, ", ")));
  const auto& scales = filter.buffer_scales;
  if (std::find(scales.begin(), scales.end(), options.buffer_scale) == scales.end())
    throw std::invalid_argument(fmt::format("method '{}' has no buffer scale {} (it accepts: {})", filter.name,
                                            options.buffer_scale, fmt::join(scales, ", ")));
}

}  // namespace bokeh
