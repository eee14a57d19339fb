#pragma once
// naive's options, parsed once from FilterOptions (the generic carrier the CLI and the sweeps fill).
// sprites runs the same gather and passes its own options, which have gather_block but no adaptive.
#include <optional>

#include "method.hpp"
#include "naive_gpu.hpp"

namespace bokeh {

struct NaiveConfig {
  std::optional<GatherBlock> gather_block;  // outputs per GPU invocation; empty: auto (naive_gather_block)
  bool adaptive = false;                    // adaptive = on (coc_tiles_gpu.hpp)
  int adaptive_tile_px = 0;                 // adaptive: the tile-max CoC map's tile side in px
};

NaiveConfig naive_config(const FilterOptions& options);

}  // namespace bokeh
