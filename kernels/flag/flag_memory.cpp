#include "flag_memory.hpp"

#include "ceil_div.hpp"
#include "flag_reduced.hpp"

namespace bokeh {

FlagBufferExtent flag_buffer_extent(int width_px, int height_px, const GatherPattern& pattern, int scale) {
  check_buffer_scale(scale);
  return {ceil_div(width_px, scale), ceil_div(height_px, scale), ceil_div(pattern.layers(), scale)};
}

double flag_paper_bytes(int width_px, int height_px, const GatherPattern& pattern, LayerPrecision precision,
                        int scale) {
  check_buffer_scale(scale);
  const double full = static_cast<double>(width_px) * height_px * pattern.layers() * bytes_per_texel(precision);
  return full / (static_cast<double>(scale) * scale * scale);
}

std::uint64_t flag_texel_bytes(int width_px, int height_px, const GatherPattern& pattern, LayerPrecision precision,
                               int scale) {
  return flag_buffer_extent(width_px, height_px, pattern, scale).texels() *
         static_cast<std::uint64_t>(bytes_per_texel(precision));
}

}  // namespace bokeh
