#pragma once
// FLAG (FLAG paper section 3.2): a horizontal pass writing a 3D buffer of per-layer cumulative row
// contributions, then a vertical pass summing layer |dy| of each row. Linear in N per pixel.
#include "gather_pattern.hpp"
#include "image.hpp"
#include "parallel.hpp"

namespace bokeh {

// How the 3D buffer stores its layers. The CPU reference rounds each stored value the way the
// GPU's image format does, so precision effects can be checked on the CPU.
enum class LayerPrecision { f32, f16 };
const char* to_string(LayerPrecision precision);
LayerPrecision layer_precision_from_string(const std::string& name);  // throws on unknown names
int bytes_per_texel(LayerPrecision precision);  // RGBA texel as the GPU stores it

struct FlagLayers {
  int width = 0, height = 0, layers = 0;
  std::vector<float> rgb;  // [(layer * height + y) * width + x] * 3
  float* at(int x, int y, int z) { return rgb.data() + ((static_cast<std::size_t>(z) * height + y) * width + x) * 3; }
  const float* at(int x, int y, int z) const {
    return rgb.data() + ((static_cast<std::size_t>(z) * height + y) * width + x) * 3;
  }
};

FlagLayers flag_horizontal(const Image& packed, const GatherPattern& pattern, LayerPrecision precision,
                           int threads = default_cpu_threads());
Image flag_vertical(const FlagLayers& layers, const GatherPattern& pattern, int threads = default_cpu_threads());
Image flag_blur(const Image& packed, const GatherPattern& pattern, LayerPrecision precision = LayerPrecision::f32,
                int threads = default_cpu_threads());

}  // namespace bokeh
