#include "flag_memory.hpp"

#include <stdexcept>
#include <string>

#include "ceil_div.hpp"

namespace bokeh {

namespace {
void check_scale(int scale) {
  if (scale != 1 && scale != 2 && scale != 4)
    throw std::invalid_argument("buffer scale must be 1 (full), 2 (half) or 4 (quarter), got " + std::to_string(scale));
}
}  // namespace

FlagBufferExtent flag_buffer_extent(int width_px, int height_px, const GatherPattern& pattern, int scale) {
  check_scale(scale);
  return {ceil_div(width_px, scale), ceil_div(height_px, scale), ceil_div(pattern.layers(), scale)};
}

double flag_paper_bytes(int width_px, int height_px, const GatherPattern& pattern, LayerPrecision precision,
                        int scale) {
  check_scale(scale);
  const double full = static_cast<double>(width_px) * height_px * pattern.layers() * bytes_per_texel(precision);
  return full / (static_cast<double>(scale) * scale * scale);
}

std::uint64_t flag_texel_bytes(int width_px, int height_px, const GatherPattern& pattern, LayerPrecision precision,
                               int scale) {
  return flag_buffer_extent(width_px, height_px, pattern, scale).texels() *
         static_cast<std::uint64_t>(bytes_per_texel(precision));
}

}  // namespace bokeh
