#version 450
// Circle-of-confusion pass: depth -> radius (px), packed with colour / discrete disc area.
// The area is one lookup: it depends on the radius only through the disc index (common.glsl), and
// area_by_index holds it for every index of the pattern (DiscAreaTable in kernels/core/gather_pattern.hpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int SPACING = 1;  // k, as params.spacing_px: a constant divisor

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) readonly buffer Depth { float depth_m[]; };
layout(std430, binding = 2) writeonly buffer Packed { vec4 packed_input[]; };
layout(std430, binding = 3) readonly buffer AreaTable { int area_by_index[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint i = index_of(p);
  const float d = depth_m[i];
  const float r = min(params.coc_scale_px * abs(d - params.focus_m) / d, params.max_radius_px);
  const int m = disc_index(r * r, SPACING, 2 * params.half_n * params.half_n);
  const int area = m < 0 ? 0 : area_by_index[max(m, 0)];
  packed_input[i] = vec4(color[i].rgb / float(area), r);
}
