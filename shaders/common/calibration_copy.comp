#version 450
// Calibration: a bandwidth-bound copy (one vec4 read and written per invocation), the device's own
// memory limit measured in the same run as the filters. The host dispatches whole workgroups over
// exactly the buffer, so there is no bounds test: on lavapipe a load under a branch that differs
// between lanes becomes one scalar load per lane, and this kernel is meant to show the best case.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Src { vec4 src[]; };
layout(std430, binding = 1) writeonly buffer Dst { vec4 dst[]; };

void main() {
  const uint i = index_of(ivec2(gl_GlobalInvocationID.xy));
  dst[i] = src[i];
}
