#version 450
// The engine-style gathers' input (kernels/core/signed_coc.hpp): colour with the CoC radius in alpha,
// negative in front of the focus plane, as Godot's blur-size pass stores it.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) readonly buffer Depth { float depth_m[]; };
layout(std430, binding = 2) readonly buffer Packed { vec4 packed_input[]; };  // .a = CoC radius px
layout(std430, binding = 3) writeonly buffer SignedCoc { vec4 signed_coc[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint i = index_of(p);
  const float r = packed_input[i].a;
  signed_coc[i] = vec4(color[i].rgb, depth_m[i] < params.focus_m ? -r : r);
}
