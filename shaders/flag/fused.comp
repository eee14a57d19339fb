#version 450
// FLAG without its 3D buffer, layer_buffer = registers (kernels/flag/flag_gpu.hpp): the horizontal and
// vertical passes fused, as the CPU reference (flag_blur) runs them. A workgroup of 8 invocations
// (lavapipe's SIMD width) is 8 neighbouring columns of one lattice phase, c = 8 b + its place, and walks
// down the rows of one row phase. At each row it bins the row's samples for its columns and sums the
// bins into layers (flag_bins and flag_layers of layers.glsl, or horizontal_shape.comp's chords with
// SHAPE, in their order of additions), then adds layer |j| to the running sum of the output row j rows
// away, moving the sums up one row in the same pass (a pass of its own spilled at N = 153: 0.74 of the
// frame without it); the output row n rows above is then complete and written. The
// sums and layers are indexed by constants only (the loops are unrolled), which lavapipe keeps in
// vector registers and its stack, where the full buffer's passes store and load every texel lane by
// lane (most of their frame, results/README.md "Layers in registers"). The vertical sums add the same
// values in the same order as vertical.comp, each layer first rounded to f16 (QUANTIZE_F16, to nearest
// as the CPU reference rounds; lavapipe's f16 image store rounds toward zero, which Vulkan also
// allows): the CPU reference's image bit for bit, and f32 the full buffer's with indexed bins.
// The row samples are loaded only in the windows of columns that the tile-max CoC map (pass tile_max)
// says can reach the workgroup's columns (reaching_windows): in a scene mostly in focus, a fraction of
// the row (results/README.md, "Loading only the samples that can reach"). A polygon's map holds areas,
// tested against the chord table's reach.
// Work per pixel: up to N row samples, each loaded once by one lane and handed to the lanes whose pattern
// holds it (lane_batch.glsl), one indexed bin add each (a load and a store per lane on lavapipe) or a
// masked add per layer in registers (MASKED_BINS, while the layers are few: flag_registers_masked), a
// sum over the layers and 2 n + 1 adds of the running sums. On a GPU this is too few invocations (k^2
// ceil(W / 8 k) workgroups) holding too many registers (3 (2 n + 1) floats of sums): auto runs it on
// CPU devices only.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "common.glsl"
#include "lane_batch.glsl"

layout(constant_id = 0) const int LAYERS = 21;  // ceil(N/2), or N for a shape's both halves
layout(constant_id = 2) const int SPACING = 2;  // k, a constant divisor for disc_index
#if SHAPE
// Any convex aperture (kernels/flag/flag_shape.hpp), as horizontal_shape.comp bins it: the input is
// shape_pack's (colour / area, area), each sample's chord in a column from the chord table. Not
// mirror-symmetric (BOTH_HALVES): N layers z = dz + n, and row y + j k adds layer n - j.
layout(constant_id = 8) const bool BOTH_HALVES = false;
layout(std430, binding = 2) readonly buffer Chords { int chords[]; };  // FlagShapeTable::chords
const int HALF = BOTH_HALVES ? (LAYERS - 1) / 2 : LAYERS - 1;          // n
// The smallest area whose shape reaches, from sample s, the nearest of the subgroup's columns first ..
// last or a column beyond it: the table's reach (after the chords) at lattice column n - (offset to it).
int reach_area(int s, int first, int last) {
  const int side = 2 * HALF + 1;
  return chords[side * (side * side + 1) + HALF - (s - clamp(s, first, last))];
}
#define TILES_BINDING 3
#else
const bool BOTH_HALVES = false;
const int HALF = LAYERS - 1;
#define TILES_BINDING 2
#endif
// The tile-max CoC map's M (kernels/core/coc_tiles.hpp, pass tile_max only; a polygon's: the largest
// area): which of a row's samples can reach the workgroup's columns, so that a row of samples mostly in
// focus loads few of them. Read from 13 layers on, a polygon's from 15 (flag_fused_reads_tile_map):
// below, its pass costs more than the loads it saves.
layout(constant_id = 7) const bool TILE_MAP = true;
#define TILE_PX_ID 6
#include "tiles.glsl"
// The bins as horizontal_bins = masked (layers.glsl): every bin tests its own range of the sample's
// disc index and adds the sample or -0.0 (which leaves every sum as it is), no dynamically indexed
// array, which lavapipe turns into a load and a store per lane: cheaper while the layers are few.
layout(constant_id = 5) const bool MASKED_BINS = false;
const int SUMS = 2 * HALF + 1;                  // output rows in flight, j = -n .. n

layout(std430, binding = 0) readonly buffer Packed { vec4 packed_input[]; };
layout(std430, binding = 1) writeonly buffer Out { vec4 result[]; };

// A layer as the buffer would hold it. f16: each channel rounded to the nearest, ties to even, as
// Imath::half rounds in the CPU reference, in vector arithmetic: packHalf2x16 and back cost a fifth of
// the frame at N = 81 on lavapipe (its unpack alone is cheap, results/README.md).
vec3 stored(vec3 layer) {
#if QUANTIZE_F16
  // To f16's spacing at the layer's exponent e, 2^(e - 10), by adding and taking away 1.5 2^(e + 13),
  // whose f32 spacing that is: to nearest, ties to even (its last bit is 0). e is clamped to [-14, 16]:
  // below, f16's subnormals (multiples of 2^-24); past 65504 a result of 2^16 or more, which scaling by
  // 2^112 and back makes infinite. Zero keeps the layer's sign. precise: no folding of either pair.
  const uvec3 bits = floatBitsToUint(layer);
  const uvec3 exponent = clamp(bits & 0x7f800000u, uvec3(113u << 23), uvec3(143u << 23));  // 2^-14 .. 2^16
  const vec3 magic = uintBitsToFloat(exponent + (13u << 23) + 0x400000u);                   // x 2^13 x 1.5
  precise vec3 rounded = (layer + magic) - magic;
  rounded = uintBitsToFloat(floatBitsToUint(rounded) | (bits & 0x80000000u));
  precise vec3 limited = rounded * 5.192296858534828e+33 * 1.925929944387236e-34;
  return limited;
#else
  return layer;
#endif
}

// Indexed bins: which of them this row has added to, a bit each (masked bins are registers, cleared).
const int TOUCHED_WORDS = MASKED_BINS ? 1 : (LAYERS + 31) / 32;

// What bin z held before this add: 0.0 at the row's first add to it, which it marks in `touched`. The
// word is chosen by selects, not an index (a dynamic index would put `touched` in scratch memory).
vec3 held(inout uint touched[TOUCHED_WORDS], vec3 bin, int z) {
  const uint bit = 1u << (z & 31);
  uint seen = 0u;
  [[unroll]] for (int w = 0; w < TOUCHED_WORDS; ++w) {
    const uint mine = z >> 5 == w ? bit : 0u;
    seen |= touched[w] & mine;
    touched[w] |= mine;
  }
  return seen == 0u ? vec3(0.0) : bin;
}

// The subgroup's samples of a row are loaded in windows of batch.x lattice columns (of column phase
// phase_x), window j = columns window0 + j batch.x .. + batch.x - 1 (with the map, window0 a multiple of
// batch.x: at k = 2 and 8 lanes, a window is a tile). Bit j % 32 of word j / 32: window j may hold a
// sample that reaches one of the subgroup's columns first .. last; at most 52 windows (n <= 100, 4 or
// more lanes).
uvec2 every_window(int window0, int last, ivec2 batch) {
  const int windows = (last + HALF - window0) / batch.x + 1;
  return uvec2(windows >= 32 ? ~0u : (1u << windows) - 1u, windows >= 64 ? ~0u : (1u << max(windows - 32, 0)) - 1u);
}
// In the rows of tile row tile_y, where the largest disc index M of the tiles under the window reaches
// the nearest of those columns (gap^2 <= M; a polygon: M at least the reach of the column from the
// window's nearest sample): the samples outside add nothing. Each lane tests every batch.x-th window.
uvec2 reaching_windows(int window0, int first, int last, ivec2 batch, int tile_y, int phase_x, int columns) {
  const int n = HALF, k = SPACING, windows = (last + n - window0) / batch.x + 1;
  uvec2 bits = uvec2(0u);
  for (int j0 = 0; j0 < windows; j0 += batch.x) {
    const int j = j0 + batch.y, lo = window0 + j * batch.x;
    const int a = max(lo, max(first - n, 0)), b = min(lo + batch.x - 1, min(last + n, columns - 1));
    const int gap = max(max(first - b, a - last), 0);
    int m = -1;
    if (j < windows && a <= b)
      for (int tile_x = (phase_x + a * k) / TILE_PX; tile_x <= (phase_x + b * k) / TILE_PX; ++tile_x)
        m = max(m, tiles[tile_element(ivec2(tile_x, tile_y))].x);
#if SHAPE
    // From the window's sample nearest to the subgroup's columns.
    const bool reaches = m >= reach_area(clamp(first, a, b), first, last);
#else
    const bool reaches = m >= gap * gap;
#endif
    const uint lanes = subgroupBallot(reaches).x << (j0 % 32);  // batch.x divides 32
    bits |= j0 < 32 ? uvec2(lanes, 0u) : uvec2(0u, lanes);
  }
  return bits;
}

void main() {
  const int n = HALF, k = SPACING;
  // Workgroup (b + blocks phase_x, phase_y): lattice columns 8 b .. 8 b + 7 of column phase phase_x.
  const int blocks = ((params.width_px + k - 1) / k + 7) / 8;
  const int phase_x = int(gl_WorkGroupID.x) / blocks, b = int(gl_WorkGroupID.x) % blocks;
  const int phase_y = int(gl_WorkGroupID.y);
  if (phase_x >= params.width_px || phase_y >= params.height_px) return;  // uniform: a frame under k px
  const int columns = (params.width_px - 1 - phase_x) / k + 1, rows = (params.height_px - 1 - phase_y) / k + 1;
  if (8 * b >= columns) return;  // uniform: a phase with fewer columns than the dispatch covers
  const int c = 8 * b + int(gl_LocalInvocationID.x), x = phase_x + c * k;
  // The subgroup's columns: first .. first + batch.x - 1 (all 8 on lavapipe with AVX2, 4 without).
  const ivec2 batch = sample_batch();
  const int first = c - batch.y, last = first + batch.x - 1;
  // sums[d]: output row t + 1 - n + d with rows .. t added, before row t + 1 (to which row t + 1 is row
  // j = n - d below). The row adds its layers and moves the sums up one row in one pass: output row t - n
  // is then complete and written.
  vec3 sums[SUMS];  // sums[SUMS - 1] stays 0: the row below the last in flight
  [[unroll]] for (int d = 0; d < SUMS; ++d) sums[d] = vec3(0.0);
#define WRITE(t, value) \
  if ((t) >= n && x < params.width_px) result[index_of(ivec2(x, phase_y + ((t) - n) * k))] = vec4(value, 1.0);
#define LAYER_FOR(d) layer[BOTH_HALVES ? (d) : abs(n - (d))]
  // Indexed bins live in lavapipe's scratch memory, where every store, even at a constant index, is one
  // masked store per lane: clearing all of them every row took 12-17% of the frame at N = 57-153
  // (results/README.md). They are cleared once; a row's first add to a bin takes 0.0 for what the bin
  // held (the bit `touched` tracks, in registers): the same values added in the same order. A channel
  // an array, not one array of vec3: a lane's three channels then share one scratch offset, extracted
  // once a lane, not once a channel (0.95-0.98 of the frame at N = 21-153).
  float bins_r[LAYERS], bins_g[LAYERS], bins_b[LAYERS];
#define BIN(z) vec3(bins_r[z], bins_g[z], bins_b[z])
#define SET_BIN(z, value) { const vec3 v_ = (value); bins_r[z] = v_.r; bins_g[z] = v_.g; bins_b[z] = v_.b; }
  [[unroll]] for (int z = 0; z < LAYERS; ++z) SET_BIN(z, vec3(0.0))
  uint touched[TOUCHED_WORDS];
  // The first window: at first - n, or rounded down to a multiple of batch.x where the map is read (its
  // windows then lie in as few tiles as can be, one more window at most).
  const int window0 = first - n - (TILE_MAP ? ((first - n) % batch.x + batch.x) % batch.x : 0);
  for (int t = 0; t < rows;) {  // a tile row of the map at a time
    const int tile_y = (phase_y + t * k) / TILE_PX;
    const uvec2 windows = TILE_MAP ? reaching_windows(window0, first, last, batch, tile_y, phase_x, columns)
                                   : every_window(window0, last, batch);
    const int rows_here = TILE_MAP ? min(rows, ((tile_y + 1) * TILE_PX - phase_y + k - 1) / k) : rows;
    for (; t < rows_here; ++t) {
      const int y = phase_y + t * k;
      if (MASKED_BINS) {
        [[unroll]] for (int z = 0; z < LAYERS; ++z) SET_BIN(z, vec3(0.0))
      }
      [[unroll]] for (int w = 0; w < TOUCHED_WORDS; ++w) touched[w] = 0u;
      // The subgroup's samples in those windows, left to right, a window a batch.
      for (uvec2 todo = windows; todo != uvec2(0u);) {
        const int s0 = window0 + batch.x * (todo.x != 0u ? findLSB(todo.x) : 32 + findLSB(todo.y));
        todo = todo.x != 0u ? uvec2(todo.x & (todo.x - 1u), todo.y) : uvec2(0u, todo.y & (todo.y - 1u));
        const int s = s0 + batch.y;
        int index_l = -1;
        const uint at_l = index_of(ivec2(phase_x + s * k, y));
        if (s >= 0 && s < columns) {
          const float coc_l = packed_input[at_l].a;
          const int gap = max(max(first - s, s - last), 0);  // to the nearest of the subgroup's columns
#if SHAPE
          const int index = int(coc_l);  // its row of the chord table
          // Else no column's pattern holds it, or its shape reaches neither the nearest of the
          // subgroup's columns nor those beyond (the table's reach, after the chords).
          if (gap <= n && index >= reach_area(s, first, last)) index_l = index;
#else
          const int index = disc_index(coc_l * coc_l, k, 2 * n * n);
          // Else no column's pattern holds it, or its disc misses them.
          if (gap <= n && index >= gap * gap) index_l = index;
#endif
        }
        // The colours of the samples that reach a column only (in a scene mostly in focus, few).
        vec3 src_l = vec3(0.0);
        if (index_l >= 0) src_l = packed_input[at_l].rgb;
        uvec4 reaching = subgroupBallot(index_l >= 0);
#if SHAPE
        while (reaching != uvec4(0)) {  // uniform exit, in the order of the samples
          // Every lane is active, so lane `from` (its place in the batch) loaded sample s0 + from.
          const uint from = take_lowest_lane(reaching);
          const int i = s0 + int(from) - c, index = subgroupShuffle(index_l, from);
          const vec3 src = subgroupShuffle(src_l, from);
          // The offset from the source to this column is -i k: lattice column n - i of the table.
          const int side = 2 * n + 1, chord = i < -n || i > n ? 0 : chords[(n - i) * (side * side + 1) + index];
          const int lo = (chord & 0xffff) - n, hi = (chord >> 16) - n - 1;
          // +colour at its far layer, -colour below its near one (both halves only); none without a chord.
          const int far = chord == 0 ? -1 : (BOTH_HALVES ? hi + n : hi);
          const int past = chord != 0 && BOTH_HALVES && lo > -n ? lo - 1 + n : -1;
          if (MASKED_BINS) {
            [[unroll]] for (int z = 0; z < LAYERS; ++z)
              SET_BIN(z, BIN(z) + (z == far ? src : (z == past ? -src : vec3(-0.0))))
          } else {
            // Without an event, 0.0 to or from bin 0: x + 0.0 and x - 0.0 are x (no bin holds -0.0).
            const int at = max(far, 0);
            SET_BIN(at, held(touched, BIN(at), at) + (far >= 0 ? src : vec3(0.0)))
            if (BOTH_HALVES) {
              const int below = max(past, 0);
              SET_BIN(below, held(touched, BIN(below), below) - (past >= 0 ? src : vec3(0.0)))
            }
          }
        }
#else
        if (MASKED_BINS) {
          while (reaching != uvec4(0)) {  // uniform exit, in the order of the samples
            // Every lane is active, so lane `from` (its place in the batch) loaded sample s0 + from.
            const uint from = take_lowest_lane(reaching);
            const int i = s0 + int(from) - c, index = subgroupShuffle(index_l, from);
            const vec3 src = subgroupShuffle(src_l, from);
            // z^2 <= d < z^2 + width as one unsigned compare (d < z^2 wraps above every width).
            const int d = i < -n || i > n ? -1 : index - i * i;
            [[unroll]] for (int z = 0; z < LAYERS; ++z) {
              const uint width = z == LAYERS - 1 ? 0x7fffffffu : uint(2 * z + 1);
              SET_BIN(z, BIN(z) + (uint(d - z * z) < width ? src : vec3(-0.0)))
            }
          }
        } else {
          // One sample ahead: the next sample's layer (its sqrt) is worked out before this one's bin
          // is updated, so the two overlap.
          bool more = reaching != uvec4(0);
          uint from = take_lowest_lane(reaching);
          int i = s0 + int(from) - c;
          int z = i < -n || i > n ? -1 : reach_layer(subgroupShuffle(index_l, from), i, n);
          vec3 src = subgroupShuffle(src_l, from);
          while (more) {  // uniform exit, in the order of the samples
            more = reaching != uvec4(0);
            const uint next = take_lowest_lane(reaching);
            const int i_next = s0 + int(next) - c;
            const int z_next = i_next < -n || i_next > n ? -1 : reach_layer(subgroupShuffle(index_l, next), i_next, n);
            const vec3 src_next = subgroupShuffle(src_l, next);
            // Without a layer, +0.0 to bin 0: the same bits as no add (no bin holds -0.0).
            const int at = max(z, 0);
            SET_BIN(at, held(touched, BIN(at), at) + (z >= 0 ? src : vec3(0.0)))
            z = z_next;
            src = src_next;
          }
        }
#endif
      }
      vec3 layer[LAYERS];
      vec3 running = vec3(0.0);
      [[unroll]] for (int z = LAYERS - 1; z >= 0; --z) {
        running += MASKED_BINS || (touched[z / 32] & (1u << (z % 32))) != 0u ? BIN(z) : vec3(0.0);
        layer[z] = stored(running);
      }
      // The same additions in the same order as adding all, then moving up.
      WRITE(t, sums[0] + LAYER_FOR(0))
      [[unroll]] for (int d = 0; d + 1 < SUMS; ++d) sums[d] = sums[d + 1] + LAYER_FOR(d + 1);
    }
  }
  for (int t = rows; t < rows + n; ++t) {  // rows past the frame add nothing
    WRITE(t, sums[0])
    [[unroll]] for (int d = 0; d + 1 < SUMS; ++d) sums[d] = sums[d + 1];
  }
}
