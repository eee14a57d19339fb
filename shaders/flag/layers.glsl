// Shared by flag_horizontal.comp and flag_bracket.comp (included after common.glsl): the f32 layer
// values of FLAG's horizontal pass for one pixel, and the bracket buffer of the bracketed precisions;
// horizontal_scan.comp takes its declarations and brackets.
// Mirrors flag_horizontal() in kernels/flag/flag.cpp, in the same order of float additions.

layout(constant_id = 0) const int LAYERS = 21;   // ceil(N/2): sizes the private arrays; n = LAYERS - 1
layout(constant_id = 2) const int SPACING = 2;   // k (= params.spacing_px), a constant divisor for disc_index
layout(constant_id = 3) const int OUTPUTS = 1;   // pixels per invocation, at stride k along the row
// How a sample lands in its bin (the option horizontal_bins, kernels/flag/flag_gpu.hpp). The bracket
// pass keeps the default, indexed: masked there gave lavapipe (Mesa 22.3.6) wrong brackets, off by
// up to 2% of the largest value, without an error (the conformance tests caught it).
layout(constant_id = 5) const bool MASKED_BINS = false;

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };

#include "layer_rows.glsl"

// bins[m][z] = the row samples whose disc reaches exactly layer z in column p0.x + m k, added left to
// right. Each loaded sample serves up to OUTPUTS columns (their offsets i - m differ); its disc
// index is computed once, so in column m it reaches layer z = min(isqrt(d), n), d = index - (i - m)^2.
// Indexed: bins[m][z] += s, after an integer square root. Masked: bin z takes s when z^2 <= d <
// (z + 1)^2 (the top bin: when z^2 <= d) and -0.0 otherwise, which leaves every sum as it is; no
// square root and no dynamically indexed array, at LAYERS compare-and-adds per sample and column.
// reach_n (uniform, <= n): samples further than reach_n k along the row reach none of the columns,
// and no disc reaches a layer above reach_n (LAYERS - 1 in the worst case; the adaptive passes take
// it from the tile-max CoC map, tiles.glsl). The bins above it stay 0.
void flag_bins(ivec2 p0, int reach_n, out vec3 bins[OUTPUTS][LAYERS]) {
  const int n = LAYERS - 1, k = SPACING;
  for (int m = 0; m < OUTPUTS; ++m)
    for (int z = 0; z < LAYERS; ++z) bins[m][z] = vec3(0.0);
  for (int i = -reach_n; i < reach_n + OUTPUTS; ++i) {
    const int sx = p0.x + i * k;
    if (sx < 0 || sx >= params.width_px) continue;
    const vec4 s = packed_input[index_of(ivec2(sx, p0.y))];
    const int index = disc_index(s.a * s.a, k, 2 * n * n);
    for (int m = 0; m < OUTPUTS; ++m) {
      const int di = i - m;
      if (di < -reach_n || di > reach_n) continue;  // uniform: outside column m's pattern
      if (MASKED_BINS) {
        const int d = index - di * di;
        for (int zz = 0; zz < LAYERS; ++zz) {
          // z^2 <= d < z^2 + width as one unsigned compare (d < z^2 wraps above every width).
          const uint width = zz > reach_n ? 0u : (zz == LAYERS - 1 ? 0x7fffffffu : uint(2 * zz + 1));
          bins[m][zz] += uint(d - zz * zz) < width ? s.rgb : vec3(-0.0);
        }
      } else {
        const int z = reach_layer(index, di, n);
        if (z >= 0 && z <= reach_n) bins[m][z] += s.rgb;
      }
    }
  }
}

// layer[z] = sum of the row's samples whose disc reaches vertical offset z k in this column: the
// bins accumulated from the outermost layer inwards.
void flag_layers(ivec2 p, int reach_n, out vec3 layer[LAYERS]) {
  vec3 bins[OUTPUTS][LAYERS];
  flag_bins(p, reach_n, bins);
  vec3 running = vec3(0.0);
  for (int z = LAYERS - 1; z >= 0; --z) {
    running += bins[0][z];
    layer[z] = running;
  }
}

#ifdef USE_BRACKETS
// Per (row y, layer z), i = y * LAYERS + z: bracket_bits[i].rgb = smallest and bracket_bits[half + i].rgb
// = largest f32 layer value of each channel along the row, as float bits (non-negative floats order
// like their bits, so atomicMin/atomicMax on uint are float min/max); .a unused. uvec4 entries so a
// reader fetches a bracket in two vector loads. Reset to 0xffffffff / 0 before flag_bracket.comp.
layout(std430, binding = 2) BRACKET_ACCESS buffer Brackets { uvec4 bracket_bits[]; };

uint bracket_index(int y, int z) { return uint(y * LAYERS + z); }
uint bracket_half() { return uint(bracket_bits.length()) / 2u; }

// (offset, scale) of row y, layer z: offset = min, scale = max - min, per channel.
void bracket_of(int y, int z, out vec3 offset, out vec3 scale) {
  const uint i = bracket_index(y, z);
  offset = uintBitsToFloat(bracket_bits[i].rgb);
  scale = uintBitsToFloat(bracket_bits[bracket_half() + i].rgb) - offset;
}
#endif
