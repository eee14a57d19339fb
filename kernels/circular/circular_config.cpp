#include "circular_config.hpp"

#include "coc_tiles_gpu.hpp"

namespace bokeh {

CircularFilterConfig circular_config(const FilterOptions& options, int far_components) {
  CircularFilterConfig c;
  c.far_components = far_components;
  c.near_components = options.integer("near_components");
  c.max_radius_px = static_cast<int>(options.pattern.max_radius_px());  // k (N - 1) / 2: a whole number
  c.precision = intermediate_precision_from_string(options.precision);
  c.adaptive = adaptive_on(options);
  return c;
}

}  // namespace bokeh
