#version 450
// Gaussian blur, horizontal pass (kernels/gaussian/gaussian.cpp): taps -R..R, edges clamped, summed
// in the CPU's order.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int RADIUS = 1;

layout(std430, binding = 0) readonly buffer Weights { float weight[]; };  // [i + R], sums to 1
layout(std430, binding = 1) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 2) writeonly buffer Blurred { vec4 blurred[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  vec3 sum = vec3(0.0);
  for (int i = -RADIUS; i <= RADIUS; ++i)
    sum += weight[i + RADIUS] * color[index_of(ivec2(clamp(p.x + i, 0, params.width_px - 1), p.y))].rgb;
  blurred[index_of(p)] = vec4(sum, 0.0);
}
