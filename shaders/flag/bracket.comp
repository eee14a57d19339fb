#version 450
// Bracket pass of the bracketed FLAG precisions: the horizontal pass's f32 layer values, not stored,
// reduced to their min and max per (row, layer, channel) into the bracket buffer. One invocation
// walks CHUNK consecutive pixels of a row and keeps its min/max in registers, then issues one
// atomicMin/atomicMax per (layer, channel): 6 ceil(N/2) atomics per CHUNK pixels, not per pixel.
// The price of bracketing: one more horizontal gather per frame, without the 3D-buffer writes.
// ADAPTIVE=1: the row samples bounded by the tile-max CoC map as in the horizontal pass; every
// pixel's layers (0 above what reaches it) still enter the min and max, so the brackets are the
// worst case's bit for bit.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

#define USE_BRACKETS
#define BRACKET_ACCESS
#include "layers.glsl"

layout(constant_id = 1) const int CHUNK = 32;

#if ADAPTIVE
#define TILE_PX_ID 4
#define TILES_BINDING 3
#include "tiles.glsl"
#endif

void main() {
  const int y = int(gl_GlobalInvocationID.y), x0 = int(gl_GlobalInvocationID.x) * CHUNK;
#if ADAPTIVE
  // Before any invocation returns: the largest D over the tiles of the subgroup's chunks.
  const int d = subgroup_tile_bounds(ivec2(x0, y), ivec2(x0 + CHUNK - 1, y)).x;
  if (d < 0) return;  // no pixel of the frame
  const int reach_n = min(isqrt(d), LAYERS - 1);
#else
  const int reach_n = LAYERS - 1;
#endif
  if (y >= params.height_px || x0 >= params.width_px) return;
  vec3 lo[LAYERS], hi[LAYERS], layer[LAYERS];
  for (int z = 0; z < LAYERS; ++z) lo[z] = vec3(uintBitsToFloat(0x7f800000u)), hi[z] = vec3(0.0);
  const int x1 = min(params.width_px, x0 + CHUNK);
  for (int x = x0; x < x1; ++x) {
    flag_layers(ivec2(x, y), reach_n, layer);
    for (int z = 0; z <= params.half_n; ++z) lo[z] = min(lo[z], layer[z]), hi[z] = max(hi[z], layer[z]);
  }
  const uint h = bracket_half();
  for (int z = 0; z <= params.half_n; ++z) {
    const uint i = bracket_index(y, z);
    const uvec3 lo_bits = floatBitsToUint(lo[z]), hi_bits = floatBitsToUint(hi[z]);
    atomicMin(bracket_bits[i].r, lo_bits.r);
    atomicMin(bracket_bits[i].g, lo_bits.g);
    atomicMin(bracket_bits[i].b, lo_bits.b);
    atomicMax(bracket_bits[h + i].r, hi_bits.r);
    atomicMax(bracket_bits[h + i].g, hi_bits.g);
    atomicMax(bracket_bits[h + i].b, hi_bits.b);
  }
}
