#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "method.hpp"

namespace bokeh {

// Outputs per invocation of the gather shader (OUTPUTS_X x OUTPUTS_Y in shaders/naive/gather.comp),
// the method's option "gather_block": "auto" picks 8x4 on CPU devices (lavapipe, where a buffer load
// costs a scalar load per lane and a block divides the loads by up to 32) and 1x1, the plain shader,
// on GPUs (not yet measured there with blocks: see the option's help).
const std::vector<std::string>& naive_gather_blocks();  // "auto", "1x1", "4x1", ...
struct GatherBlock {
  int x = 1, y = 1;
};
// The block the gather runs: `requested` (NaiveConfig::gather_block), or auto's choice when empty.
GatherBlock naive_gather_block(std::optional<GatherBlock> requested, const vk::DeviceInfo& device);
// The option itself, for methods that run naive's gather inside them (sprites).
OptionSpec naive_gather_block_option();

// Parses `options` once (naive_config) and makes the filter.
std::unique_ptr<gpu::GpuFilter> make_naive_gpu(gpu::GpuFrame& frame, const FilterOptions& options);

}  // namespace bokeh
