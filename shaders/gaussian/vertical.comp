#version 450
// Gaussian blur, vertical pass, then the blend with the sharp colour by w = clamp(r / R, 0, 1).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int RADIUS = 1;

layout(std430, binding = 0) readonly buffer Weights { float weight[]; };
layout(std430, binding = 1) readonly buffer Blurred { vec4 blurred[]; };
layout(std430, binding = 2) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 3) readonly buffer Packed { vec4 packed_input[]; };  // .a = CoC radius
layout(std430, binding = 4) writeonly buffer Out { vec4 result[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  vec3 sum = vec3(0.0);
  for (int i = -RADIUS; i <= RADIUS; ++i)
    sum += weight[i + RADIUS] * blurred[index_of(ivec2(p.x, clamp(p.y + i, 0, params.height_px - 1)))].rgb;
  const uint o = index_of(p);
  const float w = clamp(packed_input[o].a / params.max_radius_px, 0.0, 1.0);
  const vec3 sharp = color[o].rgb;
  result[o] = vec4(sharp * (1.0 - w) + sum * w, 1.0);
}
