#version 450
// Circle-of-confusion pass: depth -> radius (px), packed with colour / discrete disc area.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) readonly buffer Depth { float depth_m[]; };
layout(std430, binding = 2) writeonly buffer Packed { vec4 packed_input[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint i = index_of(p);
  const float d = depth_m[i];
  const float r = min(params.coc_scale_px * abs(d - params.focus_m) / d, params.max_radius_px);
  const float r2 = r * r;
  int area = 0;
  for (int s = -params.half_n; s <= params.half_n; ++s) {
    const int z = disc_reach_layer(r2, s * params.spacing_px, params.spacing_px, params.half_n);
    if (z >= 0) area += 2 * z + 1;
  }
  packed_input[i] = vec4(color[i].rgb / float(area), r);
}
