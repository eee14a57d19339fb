#pragma once
// FLAG's options, parsed once from FilterOptions (the generic carrier the CLI and the sweeps fill):
// every function of the method reads this instead of re-parsing strings and choice indices.
#include <optional>

#include "flag.hpp"
#include "flag_gpu.hpp"
#include "gather_pattern.hpp"
#include "method.hpp"

namespace bokeh {

struct FlagConfig {
  GatherPattern pattern;                      // full resolution (the 3D buffer's: reduced_pattern)
  LayerPrecision precision = LayerPrecision::f32;
  int buffer_scale = 1;                       // the 3D buffer at 1/buffer_scale resolution: flag_buffer_scales()
  std::optional<int> horizontal_block;        // pixels per invocation of the GPU horizontal pass; empty: auto
  FlagHorizontalBins horizontal_bins = FlagHorizontalBins::automatic;
  FlagVerticalOrder vertical_order = FlagVerticalOrder::automatic;
  bool adaptive = false;                      // adaptive = on (coc_tiles_gpu.hpp)
  int adaptive_tile_px = 0;                   // adaptive: the tile-max CoC map's tile side, px of FLAG's grid
  FlagLayerBuffer layer_buffer = FlagLayerBuffer::automatic;  // as chosen (flag_layer_buffering: as run)
  bool streamed = false;                      // layer_buffer = streamed: a ring of rows (flag_gpu.hpp)
  int band_rows = 0;                          // streamed: output rows per band; 0: auto (flag_stream_band_rows)
};

// Throws std::invalid_argument for an unknown precision, std::logic_error for a missing option.
FlagConfig flag_config(const FilterOptions& options);

}  // namespace bokeh
