#version 450
// Single-pass spiral bokeh (kernels/spiral/spiral.hpp): golden-angle spiral from the pixel out to the
// largest CoC, the background clamp, and the blog's fixed-weight blend in running-average form, with
// the same float operations in the same order as spiral_blur() on the CPU (`precise`: no fused
// multiply-add), so both agree to rounding of identical operations.
// Each invocation computes OUTPUTS adjacent pixels of a row: a sample's offset is the same for all of
// them, so they share its texels (2 (OUTPUTS + 1) loads instead of 4 OUTPUTS; lavapipe pays per load).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"

layout(constant_id = 0) const int SAMPLES = 0;          // spiral length
layout(constant_id = 1) const float CLAMP_FACTOR = 2.0;  // background CoC <= this x the pixel's
const int OUTPUTS = 4;                                   // kernels/spiral/spiral_gpu.cpp dispatches for it

// Per sample: (whole x, whole y, fx, fy), (radius - 1/2, 1 / (i + 2), 0, 0).
layout(std430, binding = 0) readonly buffer Spiral { vec4 spiral[]; };
layout(std430, binding = 1) readonly buffer SignedCoc { vec4 signed_coc[]; };
layout(std430, binding = 2) writeonly buffer Out { vec4 result[]; };

// One sample into one pixel's running average (spiral_blur's loop body).
vec3 blend(vec3 avg, vec4 s, float c, float background_limit, vec2 blend_params, bool inside) {
  float size = abs(s.a);
  if (s.a > c) size = min(size, background_limit);  // behind the pixel: clamp its CoC
  precise const float e = clamp(size - blend_params.x, 0.0, 1.0);
  precise const float m = e * e * (3.0 - 2.0 * e);  // smoothstep(r - 1/2, r + 1/2, size)
  precise const float weight = inside ? m * blend_params.y : 0.0;  // off the image: no contribution
  precise const vec3 r = avg + (s.rgb - avg) * weight;
  return r;
}

void main() {
  const int x0 = int(gl_GlobalInvocationID.x) * OUTPUTS;
  // Rows and pixels past the image's edge compute on clamped input and store nothing: every
  // invocation runs the loop, in uniform control flow, where lavapipe loads the table once per 8 lanes.
  const int y = clamp_y(int(gl_GlobalInvocationID.y));
  vec3 avg[OUTPUTS];
  float c[OUTPUTS], background_limit[OUTPUTS];
  for (int j = 0; j < OUTPUTS; ++j) {
    const vec4 centre = signed_coc[index_of(ivec2(clamp_x(x0 + j), y))];
    avg[j] = centre.rgb;
    c[j] = centre.a;
    precise const float limit = abs(centre.a) * CLAMP_FACTOR;
    background_limit[j] = limit;
  }
  for (int i = 0; i < SAMPLES; ++i) {
    const vec4 offset = spiral[2 * i];
    const vec2 blend_params = spiral[2 * i + 1].xy;
    const ivec2 whole = ivec2(offset.xy);
    const vec2 f = offset.zw;
    const int sy = y + whole.y;
    const uint row0 = uint(clamp_y(sy) * params.width_px), row1 = uint(clamp_y(sy + 1) * params.width_px);
    vec4 top[OUTPUTS + 1], bottom[OUTPUTS + 1];
    for (int k = 0; k <= OUTPUTS; ++k) {
      const uint sx = uint(clamp_x(x0 + whole.x + k));
      top[k] = signed_coc[row0 + sx];
      bottom[k] = signed_coc[row1 + sx];
    }
    for (int j = 0; j < OUTPUTS; ++j) {
      const vec4 s = bilinear_mix(f, top[j], top[j + 1], bottom[j], bottom[j + 1]);
      const bool inside = sample_inside(ivec2(x0 + j + whole.x, sy), f);
      avg[j] = blend(avg[j], s, c[j], background_limit[j], blend_params, inside);
    }
  }
  if (int(gl_GlobalInvocationID.y) >= params.height_px) return;
  for (int j = 0; j < OUTPUTS; ++j)
    if (x0 + j < params.width_px) result[index_of(ivec2(x0 + j, y))] = vec4(avg[j], 1.0);
}
