#version 450
// Gaussian blur, vertical pass, then the blend with the sharp colour by w = clamp(r / R, 0, 1);
// OUTPUTS pixels down the column per invocation.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "taps.glsl"

layout(std430, binding = 1) readonly buffer Blurred { vec4 blurred[]; };
layout(binding = 2) uniform samplerBuffer blurred_texels;  // the same buffer, read when TEXEL_LOADS
layout(std430, binding = 3) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 4) readonly buffer Packed { vec4 packed_input[]; };  // .a = CoC radius
layout(std430, binding = 5) writeonly buffer Out { vec4 result[]; };

int column;
vec3 load_blurred(int y) {
  const int i = y * params.width_px + column;
  return TEXEL_LOADS ? texelFetch(blurred_texels, i).rgb : blurred[i].rgb;
}

void main() {
  const int x = int(gl_GlobalInvocationID.x), y0 = int(gl_GlobalInvocationID.y) * OUTPUTS;
  if (x >= params.width_px || y0 >= params.height_px) return;
  column = x;
  GAUSSIAN_SUMS(sum, load_blurred, y0, params.height_px - 1)
  for (int k = 0; k < OUTPUTS; ++k) {
    if (y0 + k >= params.height_px) break;
    const uint o = index_of(ivec2(x, y0 + k));
    const float w = clamp(packed_input[o].a / params.max_radius_px, 0.0, 1.0);
    result[o] = vec4(color[o].rgb * (1.0 - w) + sum[k] * w, 1.0);
  }
}
