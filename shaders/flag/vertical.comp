#version 450
// FLAG vertical pass (paper 3.2.3): sum layer |j| of rows y + j k.
// BRACKETED=1: each texel is (v - offset) / scale of its row's bracket: read back offset + scale * q.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(constant_id = 0) const int LAYERS = 21;

layout(binding = 0, LAYER_FORMAT) uniform readonly image3D layers;
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };
#if BRACKETED
// As in layers.glsl: [y * LAYERS + z].rgb = min bits, [half + y * LAYERS + z].rgb = max bits.
layout(std430, binding = 2) readonly buffer Brackets { uvec4 bracket_bits[]; };
#endif

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const int n = params.half_n, k = params.spacing_px;
#if BRACKETED
  const uint h = uint(bracket_bits.length()) / 2u;
#endif
  vec3 sum = vec3(0.0);
  for (int j = -n; j <= n; ++j) {
    const int sy = p.y + j * k;
    if (sy < 0 || sy >= params.height_px) continue;
    const vec3 q = imageLoad(layers, ivec3(p.x, sy, abs(j))).rgb;
#if BRACKETED
    const uint i = uint(sy * LAYERS + abs(j));
    const vec3 offset = uintBitsToFloat(bracket_bits[i].rgb);
    const vec3 scale = uintBitsToFloat(bracket_bits[h + i].rgb) - offset;
    sum += offset + scale * q;
#else
    sum += q;
#endif
  }
  result[index_of(p)] = vec4(sum, 1.0);
}
