#version 450
// Hexagon, pass 1 (two outputs): out1 = blur up; out2 = (blur up + blur down-left) / 2, RGBA with
// the blurs' weighted mean signed CoC in alpha (kernels/hexagon/hexagon.hpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"
#include "hexagon.glsl"

layout(constant_id = 0) const int TAPS = 0;  // the largest CoC radius, whole pixels

layout(std430, binding = 0) readonly buffer SignedCoc { vec4 signed_coc[]; };
layout(std430, binding = 1) writeonly buffer Up { vec4 up_blur[]; };
layout(std430, binding = 2) writeonly buffer Mean { vec4 up_downleft_mean[]; };

#define BLUR_NAME blur_signed_coc
#define BLUR_SOURCE signed_coc
#include "blur.glsl"

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  // Past the edge: compute for the edge pixel, store nothing (keeps the tap loops in uniform control flow).
  const ivec2 q = min(p, ivec2(params.width_px - 1, params.height_px - 1));
  const float c = signed_coc[index_of(q)].a;
  const BlurSums up = blur_signed_coc(q, HEX_UP, c);
  const BlurSums downleft = blur_signed_coc(q, HEX_DOWNLEFT, c);
  if (outside(p)) return;
  const uint i = index_of(p);
  precise const float up_coc = up.coc_weighted / up.weight;
  up_blur[i] = vec4(up.rgb, up_coc);
  precise const vec3 mean = (up.rgb + downleft.rgb) * 0.5;
  precise const float mean_coc = (up.coc_weighted + downleft.coc_weighted) / (up.weight + downleft.weight);
  up_downleft_mean[i] = vec4(mean, mean_coc);
}
