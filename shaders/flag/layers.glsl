// Shared by flag_horizontal.comp and flag_bracket.comp (included after common.glsl): the f32 layer
// values of FLAG's horizontal pass for one pixel, and the bracket buffer of the bracketed precisions.
// Mirrors flag_horizontal() in kernels/flag.cpp, in the same order of float additions.

layout(constant_id = 0) const int LAYERS = 21;  // ceil(N/2): sizes the private arrays

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };

// layer[z] = sum of the row's samples whose disc reaches vertical offset z k in this column.
void flag_layers(ivec2 p, out vec3 layer[LAYERS]) {
  const int n = params.half_n, k = params.spacing_px;
  vec3 reach[LAYERS];
  for (int z = 0; z < LAYERS; ++z) reach[z] = vec3(0.0);
  for (int i = -n; i <= n; ++i) {
    const int sx = p.x + i * k;
    if (sx < 0 || sx >= params.width_px) continue;
    const vec4 s = packed_input[index_of(ivec2(sx, p.y))];
    const int z = disc_reach_layer(s.a * s.a, i * k, k, n);
    if (z >= 0) reach[z] += s.rgb;
  }
  vec3 running = vec3(0.0);
  for (int z = LAYERS - 1; z >= 0; --z) {
    if (z <= n) running += reach[z];
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
