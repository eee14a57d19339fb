#include "naive_config.hpp"

#include <string>

#include "coc_tiles_gpu.hpp"

namespace bokeh {

NaiveConfig naive_config(const FilterOptions& options) {
  NaiveConfig c;
  // The block's choices name it as "XxY", but for "auto" (naive_gather_blocks()).
  const std::string& block = naive_gather_blocks().at(options.choice_index("gather_block"));
  if (block != "auto") {
    const auto x = block.find('x');
    c.gather_block = GatherBlock{std::stoi(block.substr(0, x)), std::stoi(block.substr(x + 1))};
  }
  c.adaptive = adaptive_on(options);
  c.adaptive_tile_px = adaptive_tile_px(options);
  return c;
}

}  // namespace bokeh
