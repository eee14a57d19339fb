#version 450
// FLAG horizontal pass (paper 3.2.2): per pixel, bin each row sample by the last layer its disc
// reaches in this column, then accumulate outermost-first into the 3D buffer.
// BRACKETED=1: store (v - offset) / scale of the row's bracket (flag_bracket.comp) into a unorm
// format; the vertical pass undoes it. See LayerPrecision in kernels/flag.hpp.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

#if BRACKETED
#define USE_BRACKETS
#define BRACKET_ACCESS readonly
#endif
#include "layers.glsl"

layout(binding = 1, LAYER_FORMAT) uniform writeonly image3D layers;

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  vec3 layer[LAYERS];
  flag_layers(p, layer);
  for (int z = params.half_n; z >= 0; --z) {
#if BRACKETED
    vec3 offset, scale;
    bracket_of(p.y, z, offset, scale);
    vec3 q = vec3(0.0);
    for (int c = 0; c < 3; ++c)
      if (scale[c] > 0.0) q[c] = clamp((layer[z][c] - offset[c]) / scale[c], 0.0, 1.0);
    imageStore(layers, ivec3(p, z), vec4(q, 0.0));
#else
    imageStore(layers, ivec3(p, z), vec4(layer[z], 0.0));
#endif
  }
}
