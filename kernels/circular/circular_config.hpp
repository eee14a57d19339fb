#pragma once
// circular1 .. circular6's options, parsed once from FilterOptions (the generic carrier the CLI and
// the sweeps fill) into the filter's configuration, which the CPU reference, the GPU driver and the
// models read instead of re-parsing strings and choice indices.
#include "circular_separable.hpp"
#include "method.hpp"

namespace bokeh {

// far_components: the method's own count (circular<far_components>); max_radius_px: the pattern's
// k (N - 1) / 2. Throws std::invalid_argument for an unknown precision.
CircularFilterConfig circular_config(const FilterOptions& options, int far_components);

}  // namespace bokeh
