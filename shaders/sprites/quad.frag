#version 450
// The sprite's texture: the disc of its CoC radius, evaluated at this fragment's pixel centre with the
// gathers' test (integer offsets, dx^2 + dy^2 <= r^2), each covered pixel getting colour / pixel count.
// Blended additively over the gather of the rest.
#extension GL_GOOGLE_include_directive : require
#include "disc.glsl"

layout(location = 0) flat in vec3 rgb_per_pixel;
layout(location = 1) flat in ivec2 centre_px;
layout(location = 2) flat in float radius_sq;
layout(location = 0) out vec4 result;

void main() {
  const ivec2 offset = ivec2(gl_FragCoord.xy) - centre_px;  // gl_FragCoord is the pixel centre, x + 0.5
  if (!in_disc(radius_sq, offset.x, offset.y)) discard;
  result = vec4(rgb_per_pixel, 0.0);
}
