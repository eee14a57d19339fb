#version 450
// Circular separable filter, layer preparation (Garcia's near/far split, as circular_blur() on the
// CPU): w = clamp(radius / max radius, 0, 1); a pixel with w > 0 goes to the near layer if nearer than
// the focus distance, else to the far layer, as RGBA (rgb w, w); the other layer gets 0 there.
// It also reduces per-channel maxima of both layers (subgroupMax, then one atomicMax per subgroup on
// the float bits; the host zeroes them before this pass): always alpha, which tells plan.comp
// whether a field is empty, and for bracketed10 (REDUCE_COLOR_MAX) the colour maxima M too.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#include "common.glsl"

layout(constant_id = 0) const bool REDUCE_COLOR_MAX = false;

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) readonly buffer Depth { float depth_m[]; };
layout(std430, binding = 2) readonly buffer Packed { vec4 packed_input[]; };
layout(std430, binding = 3) writeonly buffer Far { vec4 far_layer[]; };
layout(std430, binding = 4) writeonly buffer Near { vec4 near_layer[]; };
layout(std430, binding = 5) buffer ChannelMax { uint max_bits[8]; };  // far RGBA, near RGBA

// Raises max_bits[i] to v (> 0). Most subgroups find the maximum already there (alpha is often 1):
// reading first spares them the contended atomic; a stale read only costs an atomic that changes
// nothing.
void raise_max(int i, float v) {
  const uint bits = floatBitsToUint(v);
  if (v > 0.0 && max_bits[i] < bits) atomicMax(max_bits[i], bits);
}

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  const bool inside = !outside(p);
  vec4 far_value = vec4(0.0), near_value = vec4(0.0);
  if (inside) {
    const uint i = index_of(p);
    const float alpha = clamp(packed_input[i].a / params.max_radius_px, 0.0, 1.0);
    if (alpha > 0.0) {
      const vec4 v = vec4(color[i].rgb * alpha, alpha);
      if (depth_m[i] < params.focus_m) near_value = v; else far_value = v;
    }
    far_layer[i] = far_value;
    near_layer[i] = near_value;
  }
  // Every invocation takes part (outside ones with 0), so no early return above.
  if (REDUCE_COLOR_MAX) {
    const vec4 far_max = subgroupMax(far_value), near_max = subgroupMax(near_value);
    if (subgroupElect()) {
      for (int c = 0; c < 4; ++c) {
        raise_max(c, far_max[c]);
        raise_max(4 + c, near_max[c]);
      }
    }
  } else {
    const float far_alpha_max = subgroupMax(far_value.a), near_alpha_max = subgroupMax(near_value.a);
    if (subgroupElect()) {
      raise_max(3, far_alpha_max);
      raise_max(7, near_alpha_max);
    }
  }
}
