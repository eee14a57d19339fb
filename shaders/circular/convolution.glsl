// Shared by horizontal.comp and vertical.comp: the circular separable filter (Garcia, GDC 2018) of
// kernels/circular/circular_separable.cpp on the GPU, see kernels/circular/circular_gpu.cpp.
// Included after common.glsl. PRECISION (a define, one SPIR-V per value) picks the intermediates:
//   0 f32:         vec4 pair per pixel: [2 p] = Re of RGBA, [2 p + 1] = Im of RGBA          32 B
//   1 f16:         uvec4 per pixel: packHalf2x16 of (Re.rg, Re.ba, Im.rg, Im.ba)            16 B
//   2 bracketed10: 3 uints per pixel, three 10-bit unorm codes each as A2B10G10R10 packs R, G, B
//                  (bits 0-9, 10-19, 20-29): (Re.r Re.g Re.b) (Re.a Im.r Im.g) (Im.b Im.a -)  12 B
//                  plus one shared box-sum buffer: uvec2 per pixel, packHalf2x16 of sum(J) / M.
// One buffer per component (bindings 4..9), so each stays under maxStorageBufferRange (128 MiB on
// lavapipe: one f32 component at 1920x1080 is 66 MB).

layout(constant_id = 0) const int COMPONENTS = 1;  // 1..6
layout(constant_id = 1) const int RADIUS = 1;      // kernel radius R: taps at -R..R
// 0 far, 1 near: which channel maxima M to use. Buckets read their field from their kernel block
// instead (field() below), so a far and a near bucket with the same kernel share one pipeline.
layout(constant_id = 2) const int LAYER = 0;
layout(constant_id = 3) const int OUTPUTS = 1;     // output pixels per invocation along the pass
// How a pass loads (both are on for lavapipe, off for GPUs; circular_gpu.cpp says why):
//   TEXEL_LOADS     its input (layer or intermediates) through uniform texel buffers (texelFetch)
//                   instead of the storage buffers;
//   SLIDING_WINDOW  the OUTPUTS inputs an invocation needs at a tap stay in registers and shift by
//                   one per tap, so each tap loads one input and one kernel tap per component
//                   instead of OUTPUTS kernel taps (more live registers).
// Every output pixel sums its taps in the same order either way: the results are bit-identical.
layout(constant_id = 4) const bool TEXEL_LOADS = false;
layout(constant_id = 5) const bool SLIDING_WINDOW = false;
// 0: the fixed-kernel filter (layer = (rgb w, w)). k >= 1: bucket k of the radius-following filter
// (circular_blur_adaptive): the layer holds (rgb, s) and the horizontal pass convolves
// (rgb, 1) max(0, 1 - |s - k|); the vertical pass adds its result to the field's sum instead of
// compositing.
layout(constant_id = 6) const int BUCKET = 0;
// Buckets run over the tiles their lists name (tiles.comp): one workgroup per entry and quarter of
// a 32 x 32 tile (gl_WorkGroupID.y), so TILE_PX = local size x OUTPUTS = 4 x local size across.
layout(constant_id = 7) const int BUCKETS = 1;

#include "tiles.glsl"

// The tile-list entry of this workgroup (bucket passes only); `pass` 0 horizontal, 1 vertical.
// Indexed by the workgroup id, so the entry (and a branch on it) is uniform across the workgroup.
#define TILE_ENTRY(pass)                                                                              \
  tile_list[tile_list_index(field(), BUCKET, pass) * tile_grid(params.width_px, params.height_px).x *   \
                tile_grid(params.width_px, params.height_px).y +                                      \
            gl_WorkGroupID.x]
ivec2 tile_origin(uint entry) {
  const int tile = int(entry & ~ZERO_TILE), columns = tile_grid(params.width_px, params.height_px).x;
  return ivec2(tile % columns, tile / columns) * TILE_PX;
}

const int TAPS = 2 * RADIUS + 1;
const float UNORM10_MAX = 1023.0;

// A uniform buffer: the taps are read at a loop-uniform index, which lavapipe turns into plain
// loads (a storage-buffer load in a loop is a per-lane loop) and GPUs serve from their constant
// caches.
layout(std140, binding = 0) uniform Kernel {
  vec4 weight[6];                // (A / normalisation, B / normalisation, 0, 0); weight[0].z: the field
  vec4 bracket[6];               // (O_re, S_re, O_im, S_im): Garcia's bracketing of Re F and Im F
  vec4 taps[COMPONENTS * TAPS];  // [c * TAPS + i]: (Re F, Im F, G'_re, G'_im), i = x + R
} kernel;

int field() { return BUCKET > 0 ? int(kernel.weight[0].z) : LAYER; }

// Written by layers.comp: per-channel maxima M of the far (0..3) and near (4..7) RGBA layers as
// float bits (non-negative floats order like their bits). The alpha maxima are always there (a
// field whose alpha max is 0 is empty), the colour maxima for bracketed10.
layout(std430, binding = 1) readonly buffer ChannelMax { uint max_bits[8]; };

layout(std430, binding = 2) buffer Layer { vec4 layer[]; };  // this pass's RGBA layer (rgb w, w)
layout(std430, binding = 3) buffer Box { uvec2 box_over_max[]; };  // bracketed10 only

#if PRECISION == 0
#define INTER_T vec4
#elif PRECISION == 1
#define INTER_T uvec4
#else
#define INTER_T uint
#endif
layout(std430, binding = 4) buffer Inter0 { INTER_T d[]; } inter0;
layout(std430, binding = 5) buffer Inter1 { INTER_T d[]; } inter1;
layout(std430, binding = 6) buffer Inter2 { INTER_T d[]; } inter2;
layout(std430, binding = 7) buffer Inter3 { INTER_T d[]; } inter3;
layout(std430, binding = 8) buffer Inter4 { INTER_T d[]; } inter4;
layout(std430, binding = 9) buffer Inter5 { INTER_T d[]; } inter5;

// Per-component code is written once as a macro X(c, buffer) and expanded for c = 0..5 with literal
// indices, each copy guarded by `c < COMPONENTS` (a specialization constant, so the guard folds when
// the pipeline is built). No private arrays indexed by a loop variable and no switch over buffers:
// llvmpipe (lavapipe) keeps every accumulator in registers only when all indices are constants.
#define FOR_EACH_COMPONENT(X) X(0, inter0) X(1, inter1) X(2, inter2) X(3, inter3) X(4, inter4) X(5, inter5)

vec4 channel_max() {
  const int o = 4 * field();
  return vec4(uintBitsToFloat(max_bits[o]), uintBitsToFloat(max_bits[o + 1]), uintBitsToFloat(max_bits[o + 2]),
              uintBitsToFloat(max_bits[o + 3]));
}

uint pack_unorm10x3(uvec3 codes) { return codes.x | (codes.y << 10) | (codes.z << 20); }
uvec3 unpack_unorm10x3(uint w) { return uvec3(w & 1023u, (w >> 10) & 1023u, (w >> 20) & 1023u); }
