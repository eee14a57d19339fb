#version 450
// FLAG horizontal pass (paper 3.2.2): per pixel, bin each row sample by the last layer its disc
// reaches in this column, then accumulate outermost-first into the 3D buffer.
// OUTPUTS (layers.glsl) pixels per invocation at stride k share each loaded row sample; every pixel
// still adds its samples in the same order, so the layers are bit for bit those of OUTPUTS = 1.
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
  // Invocation g covers block g / k of OUTPUTS k columns, phase g % k.
  const ivec2 g = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 p0 = ivec2((g.x / SPACING) * (OUTPUTS * SPACING) + g.x % SPACING, g.y);
  if (outside(p0)) return;
  vec3 bins[OUTPUTS][LAYERS];
  flag_bins(p0, bins);
  for (int m = 0; m < OUTPUTS; ++m) {
    const ivec2 p = p0 + ivec2(m * SPACING, 0);
    if (outside(p)) break;
    vec3 running = vec3(0.0);
    for (int z = LAYERS - 1; z >= 0; --z) {
      running += bins[m][z];
#if BRACKETED
      vec3 offset, scale;
      bracket_of(p.y, z, offset, scale);
      vec3 q = vec3(0.0);
      for (int c = 0; c < 3; ++c)
        if (scale[c] > 0.0) q[c] = clamp((running[c] - offset[c]) / scale[c], 0.0, 1.0);
      imageStore(layers, ivec3(p, z), vec4(q, 0.0));
#else
      imageStore(layers, ivec3(p, z), vec4(running, 0.0));
#endif
    }
  }
}
