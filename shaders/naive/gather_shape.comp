#version 450
// The naive gather for any aperture (kernels/naive/naive_shape.hpp), second pass: all N x N samples,
// a sample adding its weighted colour when its shape covers the offset from it to this pixel,
// (-i k, -j k): gauge[row -j][column -i] <= its radius. The gauges are the CPU's floats, so the shape
// test agrees with the CPU reference bit for bit; the sums run in its order. One output an invocation:
// the plain shader (gather_block applies to the disc's gather only).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Weighted { vec4 weighted[]; };
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };
layout(std430, binding = 2) readonly buffer Gauge { float gauge[]; };

#if ADAPTIVE
// Adaptive (adaptive = on): the tile map's reach index D bounds the subgroup's samples to the disc of
// index D. Every shape lies inside its disc (ShapeLattice raises its gauges until in_disc holds), so a
// sample that adds lies inside its source's disc, whose index is at most D: the same sums, bit for bit.
#define TILE_PX_ID 0
#define TILES_BINDING 3
#include "tiles.glsl"
#endif

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  const int n = params.half_n, k = params.spacing_px, side = 2 * n + 1;
#if ADAPTIVE
  // Before any invocation returns (a subgroup operation): one bound the subgroup shares.
  const int reach = subgroup_tile_bounds(p, p).x;
#else
  const int reach = 2 * n * n;  // the whole pattern
#endif
  if (outside(p)) return;
  vec3 sum = vec3(0.0);
  for (int j = -n; j <= n; ++j) {
    const int sy = p.y + j * k, columns = reach_layer(reach, j, n);
    if (sy < 0 || sy >= params.height_px || columns < 0) continue;
    const int row = (n - j) * side + n;
    for (int i = -columns; i <= columns; ++i) {
      const int sx = p.x + i * k;
      if (sx < 0 || sx >= params.width_px) continue;
      const vec4 s = weighted[index_of(ivec2(sx, sy))];
      if (gauge[row - i] <= s.a) sum += s.rgb;
    }
  }
  result[index_of(p)] = vec4(sum, 1.0);
}
