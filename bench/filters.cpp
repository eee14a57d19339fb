#include "filters.hpp"

#include <stdexcept>

#include "flag.hpp"
#include "gpu/gpu_filters.hpp"
#include "naive_gather.hpp"

namespace bokeh {

const std::vector<FilterRegistration>& registered_filters() {
  static const std::vector<FilterRegistration> filters = {
      {"naive", "naive quadratic gather, N x N samples at spacing k (FLAG paper 3.1)", {"f32"},
       [](const CpuFilterInput& in) { return naive_gather(in.packed, in.options.pattern, in.threads); },
       gpu::make_naive_gpu},
      {"flag", "FLAG: horizontal pass into a ceil(N/2)-layer 3D buffer, vertical pass (FLAG paper 3.2)",
       {"f16", "f32"},
       [](const CpuFilterInput& in) {
         return flag_blur(in.packed, in.options.pattern, layer_precision_from_string(in.options.precision),
                          in.threads);
       },
       gpu::make_flag_gpu},
  };
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

void check_precision(const FilterRegistration& filter, const std::string& precision) {
  std::string known;
  for (const auto& p : filter.precisions) {
    if (p == precision) return;
    known += (known.empty() ? "" : ", ") + p;
  }
  throw std::invalid_argument("method '" + filter.name + "' does not store intermediates as '" + precision +
                              "' (it accepts: " + known + ")");
}

}  // namespace bokeh
