#version 450
// FLAG horizontal pass for any convex aperture (kernels/flag/flag_shape.hpp, the CPU twin
// flag_shape_horizontal): per pixel, each row sample's chord [lo, hi] of its shape in this column,
// one load from the chord table by (column, area), binned as a difference along the layers
// (+colour at hi, -colour at lo - 1; halved shapes: at hi only, layer |dz|), then accumulated from
// the outermost layer inwards. OUTPUTS pixels per invocation at stride k share each loaded sample;
// every pixel adds its samples in the same order. MASKED_BINS (layers.glsl; horizontal_bins = masked,
// auto on lavapipe up to 21 layers): every bin takes +colour, -colour or -0.0 by a compare, with no
// dynamically indexed array (which lavapipe turns into a scalar load and store per lane): the same
// additions per bin as indexed, so the same layers bit for bit (x - s == x + (-s), x + -0.0 == x).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "layers.glsl"

layout(constant_id = 8) const bool BOTH_HALVES = false;  // N layers z = dz + n (else (N + 1) / 2, z = |dz|)

layout(binding = 1, LAYER_FORMAT) uniform writeonly image3D layers;
layout(std430, binding = 2) readonly buffer Chords { int chords[]; };  // FlagShapeTable::chords

void main() {
  const ivec2 g = ivec2(gl_GlobalInvocationID.xy);
  const ivec2 p0 = ivec2((g.x / SPACING) * (OUTPUTS * SPACING) + g.x % SPACING, band_row(g.y));
  if (outside_band(p0)) return;
  const int n = params.half_n, k = SPACING, side = 2 * n + 1, areas = side * side + 1;
  vec3 bins[OUTPUTS][LAYERS];
  for (int m = 0; m < OUTPUTS; ++m)
    for (int z = 0; z < LAYERS; ++z) bins[m][z] = vec3(0.0);
  for (int i = -n; i < n + OUTPUTS; ++i) {
    const int sx = p0.x + i * k;
    if (sx < 0 || sx >= params.width_px) continue;
    const vec4 s = packed_input[index_of(ivec2(sx, p0.y))];  // .a: the shape's area, a row of the table
    const int area = int(s.a);
    for (int m = 0; m < OUTPUTS; ++m) {
      const int di = i - m;
      if (di < -n || di > n) continue;  // uniform: outside column m's pattern
      // The offset from the source to pixel m is -di k: lattice column n - di.
      const int chord = chords[(n - di) * areas + area];
      if (chord == 0) continue;
      const int lo = (chord & 0xffff) - n, hi = (chord >> 16) - n - 1;
      if (MASKED_BINS) {
        const int far = BOTH_HALVES ? hi + n : hi, past = BOTH_HALVES && lo > -n ? lo - 1 + n : -1;
        for (int z = 0; z < LAYERS; ++z) bins[m][z] += z == far ? s.rgb : (z == past ? -s.rgb : vec3(-0.0));
      } else if (BOTH_HALVES) {
        bins[m][hi + n] += s.rgb;
        if (lo > -n) bins[m][lo - 1 + n] -= s.rgb;
      } else {
        bins[m][hi] += s.rgb;
      }
    }
  }
  for (int m = 0; m < OUTPUTS; ++m) {
    const ivec2 p = p0 + ivec2(m * SPACING, 0);
    if (outside(p)) break;
    vec3 running = vec3(0.0);
    for (int z = LAYERS - 1; z >= 0; --z) {
      running += bins[m][z];
      imageStore(layers, ivec3(p.x, layer_row(p.y), z), vec4(running, 0.0));
    }
  }
}
