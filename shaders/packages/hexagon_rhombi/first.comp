#version 450
// Pass 1 of the hexagonal rhombi (shaders/hexagon/first.comp, re-expressed as a package): out1 = blur
// up; out2 = (blur up + blur down-left) / 2, RGBA with the blurs' weighted mean signed CoC in alpha.
// The blur itself is the built-in's, included from the harness's shader library.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"
#include "hexagon/hexagon.glsl"

layout(constant_id = 0) const int TAPS = 0;  // the largest CoC radius, whole pixels

// The package binding convention: 2 the signed CoC (rgb, signed radius px); 5, 6 the manifest's buffers.
layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };
layout(std430, binding = 5) writeonly buffer Up { vec4 up_blur[]; };
layout(std430, binding = 6) writeonly buffer Mean { vec4 up_downleft_mean[]; };

#define BLUR_NAME blur_signed_coc
#define BLUR_SOURCE signed_coc
#include "hexagon/blur.glsl"

void main() {
  const int x0 = int(gl_GlobalInvocationID.x) * OUTPUTS;
  const int y = clamp_y(int(gl_GlobalInvocationID.y));  // past the edge: clamped input, nothing stored
  float c[OUTPUTS];
  for (int j = 0; j < OUTPUTS; ++j) c[j] = signed_coc[index_of(ivec2(clamp_x(x0 + j), y))].a;
  BlurSums up[OUTPUTS], downleft[OUTPUTS];
  blur_signed_coc(x0, y, HEX_UP, c, up);
  blur_signed_coc(x0, y, HEX_DOWNLEFT, c, downleft);
  if (int(gl_GlobalInvocationID.y) >= params.height_px) return;
  for (int j = 0; j < OUTPUTS; ++j) {
    if (x0 + j >= params.width_px) break;
    const uint i = index_of(ivec2(x0 + j, y));
    precise const float up_coc = up[j].coc_weighted / up[j].weight;
    const vec3 up_rgb = blur_result(up[j]);
    up_blur[i] = vec4(up_rgb, up_coc);
    precise const vec3 mean = (up_rgb + blur_result(downleft[j])) * 0.5;
    precise const float mean_coc =
        (up[j].coc_weighted + downleft[j].coc_weighted) / (up[j].weight + downleft[j].weight);
    up_downleft_mean[i] = vec4(mean, mean_coc);
  }
}
