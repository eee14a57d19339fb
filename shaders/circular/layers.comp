#version 450
// Circular separable filter, layer preparation, as circular_blur() on the CPU.
//   Fixed kernel (ADAPTIVE false, Garcia's near/far split): w = clamp(radius / max radius, 0, 1); a
//   pixel with w > 0 goes to the near layer if nearer than the focus distance, else to the far layer,
//   as RGBA (rgb w, w); the other layer gets 0 there.
//   Radius-following (ADAPTIVE, circular_blur_adaptive()): s = the bucket coordinate of the radius
//   (kernels/circular/circular_separable.hpp); a pixel with s > 0 goes to its field's layer as
//   (rgb, s), and both layers get (0, 0, 0, NO_BUCKET) elsewhere. Each field's bucket mask, and its
//   mask of the pixel's 32 x 32 tile (tiles.glsl), get the bits floor(s) and ceil(s) (the buckets
//   its hat weights reach).
// It also reduces per-channel maxima of both layers (subgroupMax, then one atomicMax per subgroup on
// the float bits; the host zeroes them before this pass): always alpha, which tells plan.comp
// whether a field is empty (radius-following: 1 where present), and for bracketed10
// (REDUCE_COLOR_MAX) the colour maxima M too.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#include "common.glsl"
#include "tiles.glsl"

layout(constant_id = 0) const bool REDUCE_COLOR_MAX = false;
layout(constant_id = 1) const bool ADAPTIVE = false;
layout(constant_id = 2) const int BUCKETS = 1;  // K, radius-following only

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) readonly buffer Depth { float depth_m[]; };
layout(std430, binding = 2) readonly buffer Packed { vec4 packed_input[]; };
layout(std430, binding = 3) writeonly buffer Far { vec4 far_layer[]; };
layout(std430, binding = 4) writeonly buffer Near { vec4 near_layer[]; };
// far RGBA, near RGBA maxima; far and near bucket masks (radius-following).
layout(std430, binding = 5) buffer ChannelMax { uint max_bits[8]; uint bucket_mask[2]; };
// The ramps of circular_buckets(): s = sum_k clamp(r ramp[k].x - ramp[k].y, 0, 1).
layout(std140, binding = 6) uniform Buckets { vec4 ramp[32]; ivec4 reach[32]; } buckets;
layout(std430, binding = 7) buffer TileState { uint tile_state[]; };  // see tiles.glsl

const float NO_BUCKET = -2.0;  // kNoBucket

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
  // What the maxima see: (rgb w, w) fixed; (rgb, 1) of the field's pixels radius-following.
  vec4 far_value = vec4(0.0), near_value = vec4(0.0);
  uint far_bits = 0u, near_bits = 0u;
  if (inside) {
    const uint i = index_of(p);
    const bool near = depth_m[i] < params.focus_m;
    if (ADAPTIVE) {
      const float r = packed_input[i].a;
      float s = 0.0;
      for (int k = 0; k < BUCKETS; ++k) s += clamp(r * buckets.ramp[k].x - buckets.ramp[k].y, 0.0, 1.0);
      vec4 far_out = vec4(0.0, 0.0, 0.0, NO_BUCKET), near_out = far_out;
      if (s > 0.0) {
        const vec3 rgb = color[i].rgb;
        const uint bits = (1u << uint(floor(s))) | (1u << uint(ceil(s)));
        if (near) near_out = vec4(rgb, s), near_value = vec4(rgb, 1.0), near_bits = bits;
        else far_out = vec4(rgb, s), far_value = vec4(rgb, 1.0), far_bits = bits;
      }
      far_layer[i] = far_out;
      near_layer[i] = near_out;
    } else {
      const float alpha = clamp(packed_input[i].a / params.max_radius_px, 0.0, 1.0);
      if (alpha > 0.0) {
        const vec4 v = vec4(color[i].rgb * alpha, alpha);
        if (near) near_value = v; else far_value = v;
      }
      far_layer[i] = far_value;
      near_layer[i] = near_value;
    }
  }
  // Every invocation takes part (outside ones with 0), so no early return above.
  if (ADAPTIVE) {
    // A subgroup lies within its 8 x 8 workgroup, so within one tile.
    const uint far_or = subgroupOr(far_bits), near_or = subgroupOr(near_bits);
    if (subgroupElect()) {
      if ((bucket_mask[0] & far_or) != far_or) atomicOr(bucket_mask[0], far_or);
      if ((bucket_mask[1] & near_or) != near_or) atomicOr(bucket_mask[1], near_or);
      const ivec2 grid = tile_grid(params.width_px, params.height_px), t = p / TILE_PX;
      const int tiles = grid.x * grid.y, tile = t.y * grid.x + t.x;
      if (far_or != 0u) atomicOr(tile_state[raw_mask_at(0, tile, tiles)], far_or);
      if (near_or != 0u) atomicOr(tile_state[raw_mask_at(1, tile, tiles)], near_or);
    }
  }
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
