#version 450
// Radius-following circular filter, the composite of one field after all its buckets (as
// circular_blur_adaptive() on the CPU). The field's sum S = the buckets' sum + its identity bucket,
// (rgb, 1) max(0, 1 - |s|) of the pixel's own layer value.
//   LAYER 0 (far, first): F = S. In-focus pixels (in neither layer) keep the sharp colour; far pixels
//     get F.rgb / F.a where F.a > 1e-4 (else sharp); near pixels get F itself, unnormalised, for
//     the near composite, which needs the near alpha to normalise it.
//   LAYER 1 (near, last): N = S, alpha = min(N.a, 1); behind = the far pass's result, over
//     max(F.a, 1 - alpha, 1e-4) for near pixels; out = (1 - alpha) behind + N.rgb below N.a = 1
//     (linear: the kernels' negative ringing keeps its sign, so a near light keeps its energy),
//     N.rgb / N.a from there on (covered; the ringing above 1 normalised away).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int LAYER = 0;

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) readonly buffer Far { vec4 far_layer[]; };
layout(std430, binding = 2) readonly buffer Near { vec4 near_layer[]; };
layout(std430, binding = 3) readonly buffer Sum { vec4 field_sum[]; };
layout(std430, binding = 4) buffer Out { vec4 result[]; };

const float MIN_FAR_ALPHA = 1e-4;  // kMinFarAlpha in kernels/circular/circular_separable.cpp

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint i = index_of(p);
  const vec4 own = LAYER == 0 ? far_layer[i] : near_layer[i];
  const float hat = max(0.0, 1.0 - abs(own.a));
  const vec4 sum = field_sum[i];
  const vec4 s = vec4(sum.rgb + own.rgb * hat, sum.a + hat);
  if (LAYER == 0) {
    vec4 o = vec4(color[i].rgb, 1.0);
    if (near_layer[i].a > 0.0) o = s;
    else if (own.a > 0.0 && s.a > MIN_FAR_ALPHA) o = vec4(s.rgb / s.a, 1.0);
    result[i] = o;
  } else {
    const vec4 behind = result[i];
    const float alpha = min(s.a, 1.0);
    vec3 o = behind.rgb;
    if (own.a > 0.0) o = behind.rgb / max(max(behind.a, 1.0 - alpha), MIN_FAR_ALPHA);
    o = s.a < 1.0 ? (1.0 - alpha) * o + s.rgb : s.rgb / s.a;
    result[i] = vec4(o, 1.0);
  }
}
