#version 450
// Calibration: a compute-bound loop of multiply-adds (8 independent vec4 chains, ITERATIONS deep),
// the device's arithmetic limit measured in the same run as the filters. 64 FLOPs per iteration.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int ITERATIONS = 1024;

layout(std430, binding = 0) writeonly buffer Dst { vec4 dst[]; };

void main() {
  const uint i = index_of(ivec2(gl_GlobalInvocationID.xy));  // whole workgroups: no bounds test
  const float seed = float(i) * 1e-7;
  vec4 a[8];
  for (int c = 0; c < 8; ++c) a[c] = vec4(seed + float(c));
  const vec4 m = vec4(0.999999), b = vec4(1e-7);
  for (int n = 0; n < ITERATIONS; ++n)
    for (int c = 0; c < 8; ++c) a[c] = fma(a[c], m, b);
  vec4 sum = vec4(0.0);
  for (int c = 0; c < 8; ++c) sum += a[c];
  dst[i] = sum;  // kept, so the loop cannot be removed
}
