#version 450
// FLAG horizontal pass (paper 3.2.2): per pixel, bin each row sample by the last layer its disc
// reaches in this column, then accumulate outermost-first into the 3D buffer.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int LAYERS = 21;  // ceil(N/2): sizes the private bin array

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };
layout(binding = 1, LAYER_FORMAT) uniform writeonly image3D layers;

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
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
  for (int z = n; z >= 0; --z) {
    running += reach[z];
    imageStore(layers, ivec3(p, z), vec4(running, 0.0));
  }
}
