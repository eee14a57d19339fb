#version 450
// tile_scatter, pass 3: the scatter-as-gather of Jimenez, "Next Generation Post Processing in Call of
// Duty: Advanced Warfare" (SIGGRAPH 2014), at full resolution, into output binding 4.
//
// Per pixel p (signed CoC c), with its tile's dilated (R = largest |CoC| that can reach it, n = nearest
// signed CoC):
//   - R < 0.5 px: the input (fast path);
//   - else a fixed pattern scaled to R: the pixel and RINGS rings, ring i at radius R i / RINGS with
//     8 i samples (odd rings turned half a step), 1 + 4 RINGS (RINGS + 1) taps. Each tap reads the
//     pixel nearest its offset (no filtering), so its distance d is that pixel's true distance.
//   - a sample s (signed CoC c_s) spreads its light over its own disc: weight
//        w = A / (pi max(|c_s|, 0.5)^2) x coverage,  coverage = saturate(r - d + 1),
//     where A = pi R^2 / taps is the share of the pattern's disc one sample stands for (the talk's
//     1 / (SAMPLE_COUNT SampleAlpha(tile max CoC)); the pixel's own sample stands for >= 1 px).
//   - classification as the talk's DepthCmp2, against the tile's nearest CoC rather than depth:
//     background share b = smoothstep(0, 1, c_s - n) (a ramp 1 px of CoC wide), foreground 1 - b.
//     Foreground: r = |c_s|. Background: a sample behind the pixel (c_s > c) reaches it only as far as
//     the pixel is blurred itself, r = min(|c_s|, |c|), so a blurred background never spreads over a
//     sharper surface in front of it.
//   - foreground alpha a = min(sum of foreground w, 1) (the share of p's view the near samples cover),
//     composited over the background's mean, which fills the rest of the view as far as its own share
//     reaches (min(sum of background w, 1 - a)); what neither fills is hidden: the result is normalised
//     by the view it found, as the exact reference fills hidden views with the mean of the visible.
// Samples off the image add nothing (their loads are clamped, their weight is 0: no branch).
//
// lavapipe: every per-pixel buffer load is 8 scalar loads, so the cost is the number of loads. The tap
// loops run in uniform control flow: RINGS is a specialisation constant and the rings a subgroup runs
// is one value (0 when every lane's tile is sharp: the early-out skips the loop for the whole
// subgroup; a sharp lane in a gathering subgroup runs along and keeps its input). Each invocation
// computes OUTPUTS = 4 adjacent pixels of a row (one tile, so one R and one pattern): the pattern's
// directions are computed once for all four.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_vote : require
#include "common.glsl"
#include "bilinear.glsl"  // clamp_x, clamp_y
#include "tile_scatter.glsl"

layout(constant_id = 0) const int RINGS = 4;
const int OUTPUTS = 4;  // the manifest dispatches ceil(width / 4) x height invocations for it
const float PI = 3.14159265358979;
const int TAPS = 1 + 4 * RINGS * (RINGS + 1);

layout(std430, binding = 2) readonly buffer SignedCoc { vec4 signed_coc[]; };  // (rgb, signed CoC px)
layout(std430, binding = 4) writeonly buffer Out { vec4 result[]; };
layout(std430, binding = 6) readonly buffer Dilated { vec2 tiles_dilated[]; };

// One sample into a pixel's foreground and background sums (rgb: weighted colour, a: weight).
// area: the share of the pattern the sample stands for (0: off the image).
void add_sample(inout vec4 fg, inout vec4 bg, vec4 s, float d, float c, float nearest, float area) {
  const float size = abs(s.a);
  const float spread = area / (PI * max(size, 0.5) * max(size, 0.5));
  const float background = smoothstep(0.0, 1.0, s.a - nearest);
  const float bg_size = s.a > c ? min(size, abs(c)) : size;
  const float fg_w = (1.0 - background) * spread * clamp(size - d + 1.0, 0.0, 1.0);
  const float bg_w = background * spread * clamp(bg_size - d + 1.0, 0.0, 1.0);
  fg += vec4(s.rgb, 1.0) * fg_w;
  bg += vec4(s.rgb, 1.0) * bg_w;
}

// The foreground over the background, normalised by the view they fill together.
vec3 composite(vec4 fg, vec4 bg) {
  const float alpha = min(fg.a, 1.0);
  const float behind = min(bg.a, 1.0 - alpha);
  const vec3 front = fg.a > 0.0 ? fg.rgb * (alpha / fg.a) : vec3(0.0);
  const vec3 back = bg.a > 0.0 ? bg.rgb * (behind / bg.a) : vec3(0.0);
  return (front + back) / (alpha + behind);  // > 0: the pixel's own sample always adds
}

void main() {
  const int x0 = int(gl_GlobalInvocationID.x) * OUTPUTS;
  // Rows and pixels past the image's edge compute on clamped input and store nothing, so that every
  // invocation takes part in the subgroup vote and the loops.
  const int y = clamp_y(int(gl_GlobalInvocationID.y));
  const vec2 tile = tiles_dilated[tile_index(ivec2(clamp_x(x0), y) / TILE_PX)];
  const float radius = tile.x, nearest = tile.y;
  const bool sharp = radius < 0.5;
  const int rings = subgroupAll(sharp) ? 0 : RINGS;  // uniform in the subgroup
  const float ring_px = radius / float(RINGS);
  const float area = PI * radius * radius / float(TAPS);

  vec4 centre[OUTPUTS], fg[OUTPUTS], bg[OUTPUTS];
  for (int j = 0; j < OUTPUTS; ++j) {
    centre[j] = signed_coc[index_of(ivec2(clamp_x(x0 + j), y))];
    fg[j] = vec4(0.0);
    bg[j] = vec4(0.0);
    add_sample(fg[j], bg[j], centre[j], 0.0, centre[j].a, nearest, max(area, 1.0));
  }
  for (int i = 1; i <= rings; ++i) {
    const int count = 8 * i;
    const float step = 2.0 * PI / float(count);
    const float start = (i & 1) == 1 ? 0.5 * step : 0.0;
    const vec2 turn = vec2(cos(step), sin(step));
    const float ring_radius = ring_px * float(i);
    vec2 direction = vec2(cos(start), sin(start));
    for (int k = 0; k < count; ++k) {
      const ivec2 offset = ivec2(round(ring_radius * direction));
      const float d = length(vec2(offset));
      const int sy = y + offset.y;
      const bool row_inside = sy >= 0 && sy < params.height_px;
      const uint row = uint(clamp_y(sy) * params.width_px);
      for (int j = 0; j < OUTPUTS; ++j) {
        const int sx = x0 + j + offset.x;
        const bool inside = row_inside && sx >= 0 && sx < params.width_px;
        const vec4 s = signed_coc[row + uint(clamp_x(sx))];
        add_sample(fg[j], bg[j], s, d, centre[j].a, nearest, inside ? area : 0.0);
      }
      direction = vec2(direction.x * turn.x - direction.y * turn.y, direction.x * turn.y + direction.y * turn.x);
    }
  }

  if (int(gl_GlobalInvocationID.y) >= params.height_px) return;
  for (int j = 0; j < OUTPUTS; ++j) {
    if (x0 + j >= params.width_px) break;
    const vec3 rgb = sharp ? centre[j].rgb : composite(fg[j], bg[j]);
    result[index_of(ivec2(x0 + j, y))] = vec4(rgb, 1.0);
  }
}
