#version 450
// FLAG horizontal pass, horizontal_bins = scan (kernels/flag/flag_gpu.hpp): per layer, the sum of the
// row samples whose disc reaches it, as interval sums. Layer z of column x holds sample x + i k when
// i^2 + z^2 <= its disc index (the integer test of disc.glsl, as the other binnings), i.e. when |i| <=
// w = min(isqrt(index - z^2), n): the sample adds to the interval [x - w k, x + w k] of its phase.
// One workgroup of 8 invocations (lavapipe's SIMD width) is 8 layers of one row segment of SEGMENT
// columns of one lattice phase, one invocation one layer: each sample adds itself at its interval's
// start (clamped to the segment) and subtracts itself past its end in the invocation's difference
// array, and a prefix sum along the segment gives the layer. Every lane needs every sample, but Mesa
// 22.3's lavapipe loads a shared address lane by lane (its one-load path takes only addresses built
// from constants and push constants), so the lanes load consecutive samples, one each, test them and
// hand the ones that reach a layer of the workgroup in the segment to all lanes in turn (ballot and
// shuffle, registers on lavapipe): one load and one disc index a sample, not 8 (0.86x the FLAG frame,
// results/README.md "Samples handed on by subgroup shuffle"). Work per pixel: at most
// (SEGMENT + 2 n) / SEGMENT samples per layer, O(N).
// The order of additions differs from the bins': flag_horizontal_scan() in kernels/flag/flag.cpp
// mirrors this one bit for bit.
// BRACKETED=1: stores (v - offset) / scale of the row's bracket, as horizontal.comp.
// ADAPTIVE=1: the tile-max CoC map bounds the samples by the largest disc index D reaching the
// segment's tiles, and each pixel writes the layers up to its tile's Z (as horizontal.comp). Not bit
// for bit the worst case's image: a layer no disc reaches holds the rounding residue of the intervals
// that ended before it (a few ulps of their sum), which the worst case's vertical pass adds and the
// adaptive one, reading only the layers that can be nonzero, does not.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "common.glsl"

#if BRACKETED
#define USE_BRACKETS
#define BRACKET_ACCESS readonly
#endif
#include "layers.glsl"  // LAYERS, SPACING, the packed input, the brackets (its bins are not used here)

#include "scan_segment.glsl"  // SEGMENT, the workgroup's layers, row, phase and columns
layout(binding = 1, LAYER_FORMAT) uniform writeonly image3D layers;

#if ADAPTIVE
#define TILE_PX_ID 4
#define TILES_BINDING (2 + BRACKETED)
#include "tiles.glsl"
#endif

void main() {
  const int n = LAYERS - 1, k = SPACING;
  // Layers z_first .. z_first + 7 (those past n store nothing) of row y, columns x0 + t k.
  const ScanSegment segment = scan_segment(LAYERS, k);
  const int y = segment.y, c0 = segment.c0, x0 = segment.x0, columns = segment.columns;
  const int z_first = segment.z_first, z = z_first + int(gl_LocalInvocationID.x);
  if (x0 >= params.width_px) return;  // uniform: a phase with fewer columns than the dispatch covers
#if ADAPTIVE
  // The segment's tiles: the same for every invocation of the workgroup, no subgroup reduction.
  const ivec2 bounds = tile_bounds_over(ivec2(x0, y), ivec2(x0 + (SEGMENT - 1) * k, y));
  const int reach_n = min(isqrt(max(bounds.x, 0)), n), top_layer = min(bounds.y, n);
  if (z_first > top_layer) return;  // uniform: no vertical pass reads these layers (bounds.y < 0: none)
#else
  const int reach_n = n, top_layer = n;
#endif
  // Samples j (column x0 + j k) within reach_n of the segment and inside the frame.
  const int j_lo = max(-reach_n, -c0), j_hi = min(SEGMENT - 1 + reach_n, (params.width_px - 1 - x0) / k);
  vec3 diff[SEGMENT];
  for (int t = 0; t < columns; ++t) diff[t] = vec3(0.0);
  const ivec2 batch = sample_batch();
  for (int jb = j_lo; jb <= j_hi; jb += batch.x) {
    const int jl = jb + batch.y;
    int index_l = -1;
    vec3 src_l = vec3(0.0);
    if (jl <= j_hi) {
      const vec4 s = packed_input[index_of(ivec2(x0 + jl * k, y))];
      const int gap = jl < 0 ? -jl : max(jl - (SEGMENT - 1), 0);
      const int index = disc_index(s.a * s.a, k, 2 * n * n);
      if (index >= gap * gap + z_first * z_first) {  // else it reaches none of the layers in the segment
        index_l = index;
        src_l = s.rgb;
      }
    }
    uvec4 reaching = subgroupBallot(index_l >= 0);
    // A loop of uniform exit over the reaching lanes, in the order of their samples.
    while (reaching != uvec4(0)) {
      const uint from = take_lowest_lane(reaching);
      const int j = subgroupShuffle(jl, from), index = subgroupShuffle(index_l, from);
      const vec3 src = subgroupShuffle(src_l, from);
      const int d = z > top_layer ? -1 : index - z * z;
      const int w = d < 0 ? -SEGMENT - 2 * n - 2 : min(isqrt(max(d, 0)), n);  // d < 0: no interval
      const bool starts = j + w >= 0 && j - w < columns, ends = starts && j + w + 1 < columns;
      // Without an event, +0.0 at a clamped slot: the same bits as no add (no slot holds -0.0).
      diff[clamp(j - w, 0, columns - 1)] += starts ? src : vec3(0.0);
      diff[clamp(j + w + 1, 0, columns - 1)] -= ends ? src : vec3(0.0);
    }
  }
  vec3 running = vec3(0.0);
  for (int t = 0; t < columns; ++t) {
    running += diff[t];
    const ivec2 p = ivec2(x0 + t * k, y);
#if ADAPTIVE
    const bool written = z <= top_layer && z <= tiles[tile_element_of(p)].z;
#else
    const bool written = z <= n;
#endif
#if BRACKETED
    // Quantised with the bracket pass's range of the bins' values, which the scan's may pass by its
    // rounding: clamped, within one code.
    if (written) {
      vec3 offset, scale;
      bracket_of(y, z, offset, scale);
      vec3 q = vec3(0.0);
      for (int c = 0; c < 3; ++c)
        if (scale[c] > 0.0) q[c] = clamp((running[c] - offset[c]) / scale[c], 0.0, 1.0);
      imageStore(layers, ivec3(p.x, layer_row(y), z), vec4(q, 0.0));
    }
#else
    if (written) imageStore(layers, ivec3(p.x, layer_row(y), z), vec4(running, 0.0));
#endif
  }
}
