#version 450
// A test package's pass that runs far past its estimate (tests/package_faults_test.py: the watchdog
// stops the sweep's wait and names this pass). The 16 x 16 corner the warm-up times copies, so the
// estimate is small; every other pixel spins in a loop whose exit needs a CoC above 1e30 px, which
// no frame has. lavapipe ends any loop after 65535 iterations (gallivm's loop limiter), so each
// iteration does 1024 dependent sines: about a minute a frame there, and on a GPU longer than the
// driver's timeout.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };
layout(std430, binding = 4) buffer Out { vec4 result[]; };

#define R4(s) s s s s
#define R1024(s) R4(R4(R4(R4(R4(s)))))

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p) || (p.x < 16 && p.y < 16)) return;
  float v = signed_coc[index_of(p)].a;
  for (;;) {
    R1024(v = sin(v) * 1.5 + 0.25;)
    if (signed_coc[index_of(p)].a > 1e30) break;
  }
  result[index_of(p)] = vec4(v);
}
