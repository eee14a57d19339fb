#version 450
// Reduced-resolution FLAG, pass 1 (kernels/flag/flag_reduced.hpp): each low-res pixel packs its s x s block
// of the full-res frame as FLAG input for the low-res pattern: colour sum_i w_i c_i / n, radius the
// w-weighted mean / s, with w = clamp(2 r / s - 1, 0, 1). Push constants: the LOW-RES Params.
// Same order of float operations as flag_downsample() in kernels/flag/flag_reduced.cpp.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int SCALE = 2;
layout(constant_id = 1) const int FULL_WIDTH = 1;
layout(constant_id = 2) const int FULL_HEIGHT = 1;
layout(constant_id = 3) const int SPACING = 1;  // k of the low-res pattern, a constant divisor

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };             // full res (rgb, 1)
layout(std430, binding = 1) readonly buffer PackedFull { vec4 packed_full[]; };  // full res, .a = radius
layout(std430, binding = 2) writeonly buffer PackedLow { vec4 packed_low[]; };   // low res
layout(std430, binding = 3) readonly buffer AreaTable { int area_by_index[]; };  // the low-res pattern's

float low_res_weight(float r) { return clamp(r * (2.0 / float(SCALE)) - 1.0, 0.0, 1.0); }

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  vec3 sum = vec3(0.0);
  float weight = 0.0, weighted_radius = 0.0;
  int count = 0;
  for (int y = p.y * SCALE; y < min(FULL_HEIGHT, p.y * SCALE + SCALE); ++y)
    for (int x = p.x * SCALE; x < min(FULL_WIDTH, p.x * SCALE + SCALE); ++x) {
      const uint i = uint(y * FULL_WIDTH + x);
      const float r = packed_full[i].a, w = low_res_weight(r);
      sum += w * color[i].rgb;
      weight += w;
      weighted_radius += w * r;
      ++count;
    }
  const float mean_radius = weight > 0.0 ? weighted_radius / weight : 0.0;
  const float r = min(mean_radius / float(SCALE), params.max_radius_px);
  const int m = disc_index(r * r, SPACING, 2 * params.half_n * params.half_n);
  const int area = m < 0 ? 0 : area_by_index[max(m, 0)];
  const float inv = 1.0 / (float(count) * float(area));
  packed_low[index_of(p)] = vec4(sum * inv, r);
}
