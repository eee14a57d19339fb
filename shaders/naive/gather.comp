#version 450
// Naive quadratic gather (paper 3.1): all N x N samples at spacing k, disc test, sum.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const int n = params.half_n, k = params.spacing_px;
  vec3 sum = vec3(0.0);
  for (int j = -n; j <= n; ++j) {
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    for (int i = -n; i <= n; ++i) {
      const int sx = p.x + i * k;
      if (sx < 0 || sx >= params.width_px) continue;
      const vec4 s = packed_input[index_of(ivec2(sx, sy))];
      if (in_disc(s.a * s.a, i * k, j * k)) sum += s.rgb;
    }
  }
  result[index_of(p)] = vec4(sum, 1.0);
}
