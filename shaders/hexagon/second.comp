#version 450
// Hexagon, pass 2 (three rhombi): R1 = blur of out1 down-left, R2 = blur of out2 down-right; the
// hexagon (R1 + 2 R2) / 3 computed as R1 + (R2 - R1) 2/3 (exact where both equal the input).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"
#include "hexagon.glsl"

layout(constant_id = 0) const int TAPS = 0;

layout(std430, binding = 0) readonly buffer Up { vec4 up_blur[]; };
layout(std430, binding = 1) readonly buffer Mean { vec4 up_downleft_mean[]; };
layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };  // the pixel's own CoC
layout(std430, binding = 3) writeonly buffer Out { vec4 result[]; };

#define BLUR_NAME blur_up
#define BLUR_SOURCE up_blur
#include "blur.glsl"
#undef BLUR_NAME
#undef BLUR_SOURCE
#define BLUR_NAME blur_mean
#define BLUR_SOURCE up_downleft_mean
#include "blur.glsl"

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 q = min(p, ivec2(params.width_px - 1, params.height_px - 1));
  const float c = signed_coc[index_of(q)].a;
  const BlurSums r1 = blur_up(q, HEX_DOWNLEFT, c);
  const BlurSums r2 = blur_mean(q, HEX_DOWNRIGHT, c);
  if (outside(p)) return;
  precise const vec3 hexagon = r1.rgb + (r2.rgb - r1.rgb) * HEX_TWO_THIRDS;
  result[index_of(p)] = vec4(hexagon, 1.0);
}
