#version 450
// FLAG horizontal pass (paper 3.2.2): per pixel, bin each row sample by the last layer its disc
// reaches in this column, then accumulate outermost-first into the 3D buffer.
// OUTPUTS (layers.glsl) pixels per invocation at stride k share each loaded row sample; every pixel
// still adds its samples in the same order, so the layers are bit for bit those of OUTPUTS = 1.
// BRACKETED=1: store (v - offset) / scale of the row's bracket (flag_bracket.comp) into a unorm
// format; the vertical pass undoes it. See LayerPrecision in kernels/flag/flag.hpp.
// ADAPTIVE=1 (method option adaptive = on): the tile-max CoC map (tiles.glsl) bounds the row samples
// by the largest disc index D that reaches the subgroup's pixels (uniform), and each pixel writes
// only the layers up to its tile's Z, the highest any vertical pass reads there (none: no store).
// The layers written are bit for bit the worst case's; those not written are read by nobody.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

#if BRACKETED
#define USE_BRACKETS
#define BRACKET_ACCESS readonly
#endif
#include "layers.glsl"

layout(binding = 1, LAYER_FORMAT) uniform writeonly image3D layers;

#if ADAPTIVE
#define TILE_PX_ID 4
#define TILES_BINDING (2 + BRACKETED)
#include "tiles.glsl"
#endif

void main() {
  // Invocation g covers block g / k of OUTPUTS k columns, phase g % k.
  const ivec2 g = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 p0 = ivec2((g.x / SPACING) * (OUTPUTS * SPACING) + g.x % SPACING, band_row(g.y));
#if ADAPTIVE
  // Before any invocation returns: the largest D and Z over the tiles of the subgroup's pixels.
  const ivec2 bounds = subgroup_tile_bounds(p0, p0 + ivec2((OUTPUTS - 1) * SPACING, 0));
  if (bounds.y < 0) return;  // no vertical pass reads these pixels' layers (or no pixel of the frame)
  const int reach_n = min(isqrt(max(bounds.x, 0)), LAYERS - 1), top_layer = bounds.y;
#else
  const int reach_n = LAYERS - 1, top_layer = LAYERS - 1;
#endif
  if (outside_band(p0)) return;
  vec3 bins[OUTPUTS][LAYERS];
  flag_bins(p0, reach_n, bins);
  for (int m = 0; m < OUTPUTS; ++m) {
    const ivec2 p = p0 + ivec2(m * SPACING, 0);
    if (outside(p)) break;
#if ADAPTIVE
    const int write_layer = tiles[tile_element_of(p)].z;  // this pixel's tile's Z
#else
    const int write_layer = LAYERS - 1;
#endif
    vec3 running = vec3(0.0);
    for (int z = LAYERS - 1; z >= 0; --z) {
      running += bins[m][z];
      if (z > top_layer) continue;  // uniform: above every Z of the subgroup (running is still 0)
      if (z > write_layer) continue;
#if BRACKETED
      vec3 offset, scale;
      bracket_of(p.y, z, offset, scale);
      vec3 q = vec3(0.0);
      for (int c = 0; c < 3; ++c)
        if (scale[c] > 0.0) q[c] = clamp((running[c] - offset[c]) / scale[c], 0.0, 1.0);
      imageStore(layers, ivec3(p.x, layer_row(p.y), z), vec4(q, 0.0));
#else
      imageStore(layers, ivec3(p.x, layer_row(p.y), z), vec4(running, 0.0));
#endif
    }
  }
}
