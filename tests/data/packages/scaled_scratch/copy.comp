#version 450
// A test package's pass: the input copied to the output (tests/package_faults_test.py).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };  // (rgb, signed CoC px)
layout(std430, binding = 4) writeonly buffer Out { vec4 result[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  result[index_of(p)] = vec4(signed_coc[index_of(p)].rgb, 1.0);
}
