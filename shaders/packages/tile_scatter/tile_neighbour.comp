#version 450
// tile_scatter, pass 2 (Jimenez 2014, "neighbourhood max"): per tile, the largest |CoC| and the nearest
// signed CoC over the tiles whose pixels' discs can reach it, so a pixel's gather radius covers every
// CoC that can land on it -> tiles_dilated[t] = (largest, nearest).
// The talk dilates over the 3x3 neighbouring tiles, which suffices while no CoC exceeds a tile. Here
// the CoC may reach further (max_coc = k (N - 1) / 2 up to 100+ px), so the window is RANGE tiles each
// way, RANGE = ceil(max_coc / TILE_PX) (1, the talk's 3x3, whenever max_coc <= TILE_PX), and a tile
// counts only if its largest CoC reaches: with pixel gaps gx, gy between the tiles ((|d| - 1) TILE_PX + 1
// for d tiles apart, 0 for the same row or column), gx^2 + gy^2 < (largest + 1)^2, where the gather's
// coverage saturate(|CoC| - distance + 1) stops. A tile always counts itself.
// Tile indices are clamped to the grid (a clamped tile is also visited at its true offset, where the
// reach test is the right one): no bounds test, the loop stays in uniform control flow.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "tile_scatter.glsl"

layout(constant_id = 2) const int RANGE = 1;  // ceil(max_coc / TILE_PX)

layout(std430, binding = 5) readonly buffer Tiles { vec2 tiles[]; };
layout(std430, binding = 6) writeonly buffer Dilated { vec2 tiles_dilated[]; };

int gap_px(int d) { return max(abs(d) * TILE_PX - TILE_PX + 1, 0); }

void main() {
  const ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 last = tile_grid() - 1;
  const ivec2 tc = min(t, last);
  float largest = 0.0, nearest = 3.0e38;
  for (int dy = -RANGE; dy <= RANGE; ++dy) {
    const int gy = gap_px(dy);
    for (int dx = -RANGE; dx <= RANGE; ++dx) {
      const int gx = gap_px(dx);
      const vec2 v = tiles[tile_index(clamp(tc + ivec2(dx, dy), ivec2(0), last))];
      const float reach = v.x + 1.0;
      const bool reaches = float(gx * gx + gy * gy) < reach * reach;
      largest = reaches ? max(largest, v.x) : largest;
      nearest = reaches ? min(nearest, v.y) : nearest;
    }
  }
  if (t.x >= tiles_x() || t.y >= tiles_y()) return;
  tiles_dilated[tile_index(t)] = vec2(largest, nearest);
}
