#version 450
// The sprite's texture: the disc of its CoC radius, evaluated at this fragment's pixel centre with the
// gathers' test (integer offsets, dx^2 + dy^2 <= r^2), each covered pixel getting colour / pixel count.
// SHAPE (a non-disc aperture): the shape of circumradius r, the offset's gauge read from the CPU's
// table (binding 1, offsets up to shape_half_px: kernels/sprites/sprites.hpp) and compared with r,
// the comparison the CPU reference makes on the same floats. Blended additively over the gather.
#extension GL_GOOGLE_include_directive : require
#include "disc.glsl"

layout(location = 0) flat in vec3 rgb_per_pixel;
layout(location = 1) flat in ivec2 centre_px;
layout(location = 2) flat in float radius_px;
layout(location = 0) out vec4 result;

#if SHAPE
layout(std430, binding = 1) readonly buffer Gauge { float gauge[]; };
layout(push_constant) uniform Target {
  int width_px;
  int height_px;
  int shape_half_px;
} target;
#endif

void main() {
  const ivec2 offset = ivec2(gl_FragCoord.xy) - centre_px;  // gl_FragCoord is the pixel centre, x + 0.5
#if SHAPE
  const int m = target.shape_half_px;
  if (abs(offset.x) > m || abs(offset.y) > m) discard;
  if (!(gauge[(offset.y + m) * (2 * m + 1) + offset.x + m] <= radius_px)) discard;
#else
  if (!in_disc(radius_px * radius_px, offset.x, offset.y)) discard;
#endif
  result = vec4(rgb_per_pixel, 0.0);
}
