#version 450
// tile_scatter, pass 1 (Jimenez 2014, "tile max CoC"): per TILE_PX x TILE_PX tile, the largest
// |signed CoC| and the nearest (most negative) signed CoC of its pixels -> tiles[t] = (largest, nearest).
// One invocation per tile. The loop always runs TILE_PX^2 taps, at coordinates clamped into the frame
// (a repeated edge pixel changes neither max nor min): no bounds test, so the loop stays in uniform
// control flow, and invocations past the tile grid compute on the last tile and store nothing.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "bilinear.glsl"  // clamp_x, clamp_y
#include "tile_scatter.glsl"

layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };  // (rgb, signed CoC px)
layout(std430, binding = 5) writeonly buffer Tiles { vec2 tiles[]; };

void main() {
  const ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 lo = min(t, tile_grid() - 1) * TILE_PX;
  float largest = 0.0, nearest = 3.0e38;
  for (int dy = 0; dy < TILE_PX; ++dy) {
    const uint row = uint(clamp_y(lo.y + dy) * params.width_px);
    for (int dx = 0; dx < TILE_PX; ++dx) {
      const float c = signed_coc[row + uint(clamp_x(lo.x + dx))].a;
      largest = max(largest, abs(c));
      nearest = min(nearest, c);
    }
  }
  if (t.x >= tiles_x() || t.y >= tiles_y()) return;
  tiles[tile_index(t)] = vec2(largest, nearest);
}
