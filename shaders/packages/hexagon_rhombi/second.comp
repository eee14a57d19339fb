#version 450
// Pass 2 of the hexagonal rhombi (shaders/hexagon/second.comp, re-expressed as a package): R1 = blur
// of out1 down-left, R2 = blur of out2 down-right; the hexagon (R1 + 2 R2) / 3 as R1 + (R2 - R1) 2/3.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"
#include "hexagon/hexagon.glsl"

layout(constant_id = 0) const int TAPS = 0;

layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };  // the pixel's own CoC
layout(std430, binding = 4) writeonly buffer Out { vec4 result[]; };
layout(std430, binding = 5) readonly buffer Up { vec4 up_blur[]; };
layout(std430, binding = 6) readonly buffer Mean { vec4 up_downleft_mean[]; };

#define BLUR_NAME blur_up
#define BLUR_SOURCE up_blur
#include "hexagon/blur.glsl"
#undef BLUR_NAME
#undef BLUR_SOURCE
#define BLUR_NAME blur_mean
#define BLUR_SOURCE up_downleft_mean
#include "hexagon/blur.glsl"

void main() {
  const int x0 = int(gl_GlobalInvocationID.x) * OUTPUTS;
  const int y = clamp_y(int(gl_GlobalInvocationID.y));
  float c[OUTPUTS];
  for (int j = 0; j < OUTPUTS; ++j) c[j] = signed_coc[index_of(ivec2(clamp_x(x0 + j), y))].a;
  BlurSums r1[OUTPUTS], r2[OUTPUTS];
  blur_up(x0, y, HEX_DOWNLEFT, c, r1);
  blur_mean(x0, y, HEX_DOWNRIGHT, c, r2);
  if (int(gl_GlobalInvocationID.y) >= params.height_px) return;
  for (int j = 0; j < OUTPUTS; ++j) {
    if (x0 + j >= params.width_px) break;
    const vec3 a = blur_result(r1[j]), b = blur_result(r2[j]);
    precise const vec3 hexagon = a + (b - a) * HEX_TWO_THIRDS;
    result[index_of(ivec2(x0 + j, y))] = vec4(hexagon, 1.0);
  }
}
