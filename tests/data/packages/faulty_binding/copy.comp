#version 450
// A test package's pass binding a buffer (5) its manifest does not declare: refused at load.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };
layout(std430, binding = 4) writeonly buffer Out { vec4 result[]; };
layout(std430, binding = 5) readonly buffer Extra { vec4 extra[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  result[index_of(p)] = vec4(signed_coc[index_of(p)].rgb, 1.0) + extra[0];
}
