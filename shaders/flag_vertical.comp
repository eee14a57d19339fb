#version 450
// FLAG vertical pass (paper 3.2.3): sum layer |j| of rows y + j k.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(binding = 0, LAYER_FORMAT) uniform readonly image3D layers;
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const int n = params.half_n, k = params.spacing_px;
  vec3 sum = vec3(0.0);
  for (int j = -n; j <= n; ++j) {
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    sum += imageLoad(layers, ivec3(p.x, sy, abs(j))).rgb;
  }
  result[index_of(p)] = vec4(sum, 1.0);
}
