#include "flag.hpp"

#include <stdexcept>

#include <Imath/half.h>

namespace bokeh {

const char* to_string(LayerPrecision precision) { return precision == LayerPrecision::f32 ? "f32" : "f16"; }

LayerPrecision layer_precision_from_string(const std::string& name) {
  if (name == "f32") return LayerPrecision::f32;
  if (name == "f16") return LayerPrecision::f16;
  throw std::invalid_argument("unknown layer precision '" + name + "' (expected f32 or f16)");
}

int bytes_per_texel(LayerPrecision precision) { return precision == LayerPrecision::f32 ? 16 : 8; }

FlagLayers flag_horizontal(const Image& packed, const GatherPattern& p, LayerPrecision precision, int threads) {
  const int n = p.half(), k = p.spacing_px;
  FlagLayers out{packed.width, packed.height, p.layers(), {}};
  out.rgb.assign(static_cast<std::size_t>(out.width) * out.height * out.layers * 3, 0.0f);
  parallel_rows(packed.height, threads, [&](int y) {
    std::vector<float> reach(static_cast<std::size_t>(out.layers) * 3);
    for (int x = 0; x < packed.width; ++x) {
      // Gather: each row sample lands in the slot of the last layer its disc reaches in column x...
      std::fill(reach.begin(), reach.end(), 0.0f);
      for (int i = -n; i <= n; ++i) {
        const int sx = x + i * k;
        if (sx < 0 || sx >= packed.width) continue;
        const float* s = packed.px(sx, y);
        const int z = disc_reach_layer(s[3] * s[3], i * k, k, n);
        if (z < 0) continue;
        for (int c = 0; c < 3; ++c) reach[z * 3 + c] += s[c];
      }
      // ...then accumulate from the outermost layer inwards: layer z holds every disc reaching >= z.
      float running[3] = {0, 0, 0};
      for (int z = n; z >= 0; --z) {
        float* dst = out.at(x, y, z);
        for (int c = 0; c < 3; ++c) {
          running[c] += reach[z * 3 + c];
          dst[c] = precision == LayerPrecision::f16 ? static_cast<float>(Imath::half(running[c])) : running[c];
        }
      }
    }
  });
  return out;
}

Image flag_vertical(const FlagLayers& layers, const GatherPattern& p, int threads) {
  const int n = p.half(), k = p.spacing_px;
  Image out(layers.width, layers.height, 3);
  parallel_rows(layers.height, threads, [&](int y) {
    for (int x = 0; x < layers.width; ++x) {
      float sum[3] = {0, 0, 0};
      for (int j = -n; j <= n; ++j) {
        const int sy = y + j * k;
        if (sy < 0 || sy >= layers.height) continue;
        const float* v = layers.at(x, sy, j < 0 ? -j : j);
        for (int c = 0; c < 3; ++c) sum[c] += v[c];
      }
      float* o = out.px(x, y);
      for (int c = 0; c < 3; ++c) o[c] = sum[c];
    }
  });
  return out;
}

Image flag_blur(const Image& packed, const GatherPattern& p, LayerPrecision precision, int threads) {
  return flag_vertical(flag_horizontal(packed, p, precision, threads), p, threads);
}

}  // namespace bokeh
