#version 450
// Reduced-resolution FLAG, pass 4 (kernels/flag/flag_reduced.hpp): out = (1 - w(r)) colour + bilinear of
// the low-res FLAG output at ((x + 0.5) / s - 0.5, (y + 0.5) / s - 0.5), edges clamped. Push
// constants: the FULL-RES Params. Same float operations as flag_upsample() in kernels/flag/flag_reduced.cpp.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int SCALE = 2;
layout(constant_id = 1) const int LOW_WIDTH = 1;
layout(constant_id = 2) const int LOW_HEIGHT = 1;

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };             // full res (rgb, 1)
layout(std430, binding = 1) readonly buffer PackedFull { vec4 packed_full[]; };  // full res, .a = radius
layout(std430, binding = 2) readonly buffer Low { vec4 blurred_low[]; };         // low-res FLAG output
layout(std430, binding = 3) writeonly buffer Out { vec4 result[]; };

vec3 low(int x, int y) { return blurred_low[uint(y * LOW_WIDTH + x)].rgb; }

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const float inv_scale = 1.0 / float(SCALE);
  const float u = (float(p.x) + 0.5) * inv_scale - 0.5, v = (float(p.y) + 0.5) * inv_scale - 0.5;
  const float fu = floor(u), fv = floor(v);
  const float ax = u - fu, ay = v - fv;
  const int x0 = clamp(int(fu), 0, LOW_WIDTH - 1), x1 = clamp(int(fu) + 1, 0, LOW_WIDTH - 1);
  const int y0 = clamp(int(fv), 0, LOW_HEIGHT - 1), y1 = clamp(int(fv) + 1, 0, LOW_HEIGHT - 1);
  const vec3 top = low(x0, y0) * (1.0 - ax) + low(x1, y0) * ax;
  const vec3 bottom = low(x0, y1) * (1.0 - ax) + low(x1, y1) * ax;
  const vec3 b = top * (1.0 - ay) + bottom * ay;
  const uint i = index_of(p);
  const float sharp = 1.0 - clamp(packed_full[i].a * (2.0 / float(SCALE)) - 1.0, 0.0, 1.0);
  result[i] = vec4(sharp * color[i].rgb + b, 1.0);
}
