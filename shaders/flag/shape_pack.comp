#version 450
// FLAG for any aperture (kernels/flag/flag_shape.hpp), first pass: each source's colour over its
// shape's area m on the pattern (the number of pattern offsets whose gauge is <= its radius: an upper
// bound search in naive's sorted gauges, as ShapeLattice::area does), and m as a float (exact below
// 2^24): the horizontal pass's row into the chord table, computed once here rather than per sample.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };  // .a: the radius (CoC pass)
layout(std430, binding = 1) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 2) readonly buffer Sorted { float sorted_gauge[]; };
layout(std430, binding = 3) writeonly buffer Weighted { vec4 weighted[]; };

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint at = index_of(p);
  const float r = packed_input[at].a;
  const int side = 2 * params.half_n + 1;
  int lo = 0, hi = side * side;
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (sorted_gauge[mid] <= r) lo = mid + 1;
    else hi = mid;
  }
  weighted[at] = vec4(color[at].rgb / float(lo), float(lo));
}
