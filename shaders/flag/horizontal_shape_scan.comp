#version 450
// FLAG horizontal pass for a non-disc aperture, horizontal_bins = scan (kernels/flag/flag_shape.hpp; the
// disc's is horizontal_scan.comp, whose structure this follows): per layer, the sum of the row samples
// whose shape covers it, as interval sums. In a segment (columns x0 + t k), the sample at column x0 + j k
// reaches output column t in layer z when the shape of its area m covers lattice column t - j + n (the
// offset from source to pixel is (t - j) k) in the layer's row: when t - j is in [a - n, b - n], [a, b]
// the row section of (m, z) (FlagShapeTable::sections), so it adds to one interval of columns a layer.
// One workgroup of 8 invocations is 8 layers of one row segment of SEGMENT columns of one lattice phase
// (scan_segment.glsl), one invocation one layer: each sample adds itself at its interval's start
// (clamped to the segment) and subtracts itself past its end in the invocation's difference array, and
// a prefix sum along the segment gives the layer. The lanes load consecutive samples, one each, and
// hand on those whose group's union of sections reaches a column of the segment (as the disc's). Each
// invocation loads its own layer's section as one int, not the group's two ivec4 picked from by selects
// on the lane: lavapipe's one-load path takes only addresses built from constants and push constants
// (nir_src_is_always_uniform in lp_bld_nir_soa.c), which these (the workgroup id, a loaded area) are
// not, so an ivec4 at the address the 8 lanes share costs a scalar load per lane and component.
// Measured on lavapipe 22.3.6 (`bokehbench ab`, 800x600 hoops, blades6, k = 2, f16, 8 paired rounds,
// beside another helper's builds), the FLAG frame took 0.925 [0.902, 0.945] (N = 41) and 0.958
// [0.936, 0.982] (N = 153) of the ivec4 form's time.
// Order of additions: flag_shape_horizontal_scan() in kernels/flag/flag_shape.cpp, bit for bit.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "common.glsl"
#include "layers.glsl"  // LAYERS (the shape's layer count), SPACING; packed_input: colour / area, area
#include "scan_segment.glsl"

layout(binding = 1, LAYER_FORMAT) uniform writeonly image3D layers;
// FlagShapeTable::sections: per (area m, group g of 8 layers), 12 ints (three ivec4) from (m G + g) 12:
// the row sections of layers 8 g .. 8 g + 7, then their union; each packed (b + 1) << 16 | a, 0: none.
layout(std430, binding = 2) readonly buffer Sections { int sections[]; };

// Offsets t - j of the output columns an entry reaches: [first, last]; entry 0 gives last < first.
int first_of(int entry, int n) { return (entry & 0xffff) - n; }
int last_of(int entry, int n) { return (entry >> 16) - 1 - n; }

void main() {
  const int n = params.half_n, k = SPACING, groups = (LAYERS + 7) / 8;
  const ScanSegment segment = scan_segment(LAYERS, k);
  const int y = segment.y, c0 = segment.c0, x0 = segment.x0, lane = int(gl_LocalInvocationID.x);
  const int g = segment.z_first / 8, z = segment.z_first + lane;  // layers past LAYERS store nothing
  if (x0 >= params.width_px) return;  // uniform: a phase with fewer columns than the dispatch covers
  // Samples j (column x0 + j k) within n of the segment and inside the frame.
  const int j_lo = max(-n, -c0), j_hi = min(SEGMENT - 1 + n, (params.width_px - 1 - x0) / k);
  const int columns = segment.columns;
  vec3 diff[SEGMENT];
  for (int t = 0; t < columns; ++t) diff[t] = vec3(0.0);
  // As horizontal_scan.comp: each sample whose group's union reaches a column of the segment is
  // handed to all lanes in turn.
  const ivec2 batch = sample_batch();
  for (int jb = j_lo; jb <= j_hi; jb += batch.x) {
    const int jl = jb + batch.y;
    int at_l = -1;  // the sample's (m, g) entry; -1: it reaches no column of the segment
    vec3 src_l = vec3(0.0);
    if (jl <= j_hi) {
      const vec4 s = packed_input[index_of(ivec2(x0 + jl * k, y))];
      const int at = (int(s.a) * groups + g) * 12, reach = sections[at + 8];
      if (reach != 0 && jl + last_of(reach, n) >= 0 && jl + first_of(reach, n) < SEGMENT) {
        at_l = at;
        src_l = s.rgb;
      }
    }
    uvec4 reaching = subgroupBallot(at_l >= 0);
    while (reaching != uvec4(0)) {  // uniform exit, in the order of the samples
      const uint from = take_lowest_lane(reaching);
      const int j = subgroupShuffle(jl, from), entry = sections[subgroupShuffle(at_l, from) + lane];
      const vec3 src = subgroupShuffle(src_l, from);
      const int first = j + first_of(entry, n), last = j + last_of(entry, n);
      const bool starts = entry != 0 && last >= 0 && first < columns, ends = starts && last + 1 < columns;
      // Without an event, +0.0 at a clamped slot: the same bits as no add (no slot holds -0.0).
      diff[clamp(first, 0, columns - 1)] += starts ? src : vec3(0.0);
      diff[clamp(last + 1, 0, columns - 1)] -= ends ? src : vec3(0.0);
    }
  }
  vec3 running = vec3(0.0);
  for (int t = 0; t < columns; ++t) {
    running += diff[t];
    if (z < LAYERS) imageStore(layers, ivec3(x0 + t * k, layer_row(y), z), vec4(running, 0.0));
  }
}
