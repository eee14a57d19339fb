#version 450
// Bokeh detection (de Rousiers & Pettineo, pass 2): a pixel whose luminance exceeds the mean
// luminance of its 8 neighbours (edge-clamped) by more than THRESHOLD, and whose CoC radius is at
// least MIN_RADIUS_PX (Unreal's r.DOF.Scatter.MinCocRadius), is appended to the sprite buffer with an
// atomic counter that is also the indirect draw's instance count. Its colour leaves the gather
// input (packed rgb = 0, in place: the CoC pass rewrites it every frame). Past MAX_SPRITES the pixel
// is counted as overflow and stays in the gather. The same float operations, in the same order, as
// kernels/sprites/sprites.cpp (`precise`: no fused multiply-adds), so both detect the same pixels.
// SHAPE (a non-disc aperture): binding 1 is naive's shape-weighted input (colour / shape area, radius),
// whose sprites' colour this pass takes out in the same way, and a sprite's pixel count is how many
// of the sorted gauges (binding 4, SHAPE_OFFSETS of them) are <= its radius (ShapeLattice::area).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "sprite.glsl"

layout(constant_id = 0) const int MAX_SPRITES = 1;
layout(constant_id = 1) const float THRESHOLD = 1.0;
layout(constant_id = 2) const float MIN_RADIUS_PX = 0.0;

layout(std430, binding = 0) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 1) buffer Packed { vec4 packed_input[]; };  // (rgb / gather area, radius px)
layout(std430, binding = 2) buffer Counters {
  uint vertex_count;    // VkDrawIndirectCommand: 6 (two triangles a sprite)
  uint instance_count;  //   the sprites appended (never above MAX_SPRITES)
  uint first_vertex;
  uint first_instance;
  uint overflowed;      // detected past MAX_SPRITES
  uint quad_pixels_low;   // pixels the appended sprites' quads cover (fragments rasterised),
  uint quad_pixels_high;  // a 64-bit count carried by hand
} counters;
layout(std430, binding = 3) writeonly buffer Sprites { Sprite sprites[]; };
#if SHAPE
layout(constant_id = 3) const int SHAPE_OFFSETS = 1;
layout(std430, binding = 4) readonly buffer Sorted { float sorted_gauge[]; };
#endif

precise float luminance(vec3 c) { return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b; }

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint i = index_of(p);
  const float r = packed_input[i].a;
  if (!(r >= MIN_RADIUS_PX)) return;
  const ivec2 last = ivec2(params.width_px - 1, params.height_px - 1);
  precise vec3 neighbours = vec3(0.0);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (dx != 0 || dy != 0) neighbours += color[index_of(clamp(p + ivec2(dx, dy), ivec2(0), last))].rgb;
  const vec3 c = color[i].rgb;
  precise const float contrast = luminance(c) - luminance(neighbours * 0.125);
  if (!(contrast > THRESHOLD)) return;

  // The counter is the draw's instance count: a pixel past the maximum takes its increment back, so
  // the count ends at min(detected, MAX_SPRITES) and slots 0.. are each written once.
  const uint slot = atomicAdd(counters.instance_count, 1u);
  if (slot >= uint(MAX_SPRITES)) {
    atomicAdd(counters.instance_count, 0xffffffffu);
    atomicAdd(counters.overflowed, 1u);
    return;
  }
  const int f = quad_half_px(r);
#if SHAPE
  int count = 0, hi = SHAPE_OFFSETS;  // upper bound: the first gauge > r
  while (count < hi) {
    const int mid = (count + hi) / 2;
    if (sorted_gauge[mid] <= r) count = mid + 1;
    else hi = mid;
  }
#else
  const float r2 = r * r;
  int count = 0;
  for (int dx = -f; dx <= f; ++dx) {
    const int z = disc_reach_layer(r2, dx, 1, f);
    if (z >= 0) count += 2 * z + 1;
  }
#endif
  const uint quad = uint(2 * f + 1) * uint(2 * f + 1);
  if (atomicAdd(counters.quad_pixels_low, quad) + quad < quad) atomicAdd(counters.quad_pixels_high, 1u);
  precise const vec3 rgb = c * (1.0 / float(count));
  sprites[slot] = Sprite(p, r, float(count), vec4(rgb, 0.0));
  packed_input[i] = vec4(0.0, 0.0, 0.0, r);
}
