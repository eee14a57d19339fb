#version 450
// Single-pass spiral bokeh (kernels/spiral/spiral.hpp): golden-angle spiral from the pixel out to the
// largest CoC, the background clamp, and the blog's fixed-weight blend in running-average form. The
// same float operations in the same order as spiral_blur() on the CPU (`precise`: no fused
// multiply-add), so both agree to rounding of identical operations.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"

layout(constant_id = 0) const int SAMPLES = 0;          // spiral length
layout(constant_id = 1) const float CLAMP_FACTOR = 2.0;  // background CoC <= this x the pixel's

layout(std430, binding = 0) readonly buffer Spiral { vec4 spiral[]; };  // (dx, dy, radius - 1/2, 1 / (i + 2))
layout(std430, binding = 1) readonly buffer SignedCoc { vec4 signed_coc[]; };
layout(std430, binding = 2) writeonly buffer Out { vec4 result[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  // Invocations past the image's edge run the loop on the edge pixel and skip only the store: the loop
  // stays in uniform control flow, where lavapipe loads the spiral table once per 8 lanes.
  const ivec2 q = min(p, ivec2(params.width_px - 1, params.height_px - 1));
  const vec4 centre = signed_coc[index_of(q)];
  precise vec3 avg = centre.rgb;
  const float c = centre.a;
  precise const float background_limit = abs(c) * CLAMP_FACTOR;
  for (int i = 0; i < SAMPLES; ++i) {
    const vec4 t = spiral[i];
    precise const vec2 pos = vec2(q) + t.xy;
    const Bilinear b = bilinear_at(pos);
    const vec4 s = bilinear_mix(b, signed_coc[b.i00], signed_coc[b.i10], signed_coc[b.i01], signed_coc[b.i11]);
    float size = abs(s.a);
    if (s.a > c) size = min(size, background_limit);  // behind the pixel: clamp its CoC
    precise const float e = clamp(size - t.z, 0.0, 1.0);
    precise const float m = e * e * (3.0 - 2.0 * e);  // smoothstep(r - 1/2, r + 1/2, size)
    precise const float weight = b.inside ? m * t.w : 0.0;  // off the image: no contribution
    avg = avg + (s.rgb - avg) * weight;
  }
  if (!outside(p)) result[index_of(p)] = vec4(avg, 1.0);
}
