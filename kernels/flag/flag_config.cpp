#include "flag_config.hpp"

#include <string>

#include "coc_tiles_gpu.hpp"

namespace bokeh {

FlagConfig flag_config(const FilterOptions& options) {
  FlagConfig c;
  c.pattern = options.pattern;
  c.precision = layer_precision_from_string(options.precision);
  c.buffer_scale = options.buffer_scale;
  // The block's choices name their pixel counts, but for "auto" (flag_horizontal_blocks()).
  const std::string& block = flag_horizontal_blocks().at(options.choice_index("horizontal_block"));
  if (block != "auto") c.horizontal_block = std::stoi(block);
  c.horizontal_bins = options.choice<FlagHorizontalBins>("horizontal_bins");
  c.vertical_order = options.choice<FlagVerticalOrder>("vertical_order");
  c.adaptive = adaptive_on(options);
  c.adaptive_tile_px = adaptive_tile_px(options);
  c.layer_buffer = options.choice<FlagLayerBuffer>("layer_buffer");
  c.streamed = c.layer_buffer == FlagLayerBuffer::streamed;
  c.band_rows = options.integer("band_rows");
  return c;
}

}  // namespace bokeh
