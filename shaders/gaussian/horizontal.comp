#version 450
// Gaussian blur, horizontal pass (kernels/gaussian/gaussian.cpp): taps -R..R, edges clamped, each
// output summed in the CPU's order; OUTPUTS pixels along the row per invocation.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "taps.glsl"

layout(std430, binding = 1) readonly buffer Color { vec4 color[]; };
layout(binding = 2) uniform samplerBuffer color_texels;  // the same buffer, read when TEXEL_LOADS
layout(std430, binding = 3) writeonly buffer Blurred { vec4 blurred[]; };

int row;
vec3 load_color(int x) {
  const int i = row + x;
  return TEXEL_LOADS ? texelFetch(color_texels, i).rgb : color[i].rgb;
}

void main() {
  const int x0 = int(gl_GlobalInvocationID.x) * OUTPUTS, y = int(gl_GlobalInvocationID.y);
  if (x0 >= params.width_px || y >= params.height_px) return;
  row = y * params.width_px;
  GAUSSIAN_SUMS(sum, load_color, x0, params.width_px - 1)
  for (int k = 0; k < OUTPUTS; ++k)
    if (x0 + k < params.width_px) blurred[row + x0 + k] = vec4(sum[k], 0.0);
}
