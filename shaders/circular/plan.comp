#version 450
// Circular separable filter, after layers.comp: the indirect dispatch sizes of the passes that an
// empty field (alpha max 0) or bucket can skip, decided on the GPU, so a frame needs no read-back.
// One invocation.
//   Fixed kernel: an empty field's horizontal pass, and the near vertical pass, get no workgroups;
//   the far vertical pass always runs (it writes the output) and skips its own convolution
//   (vertical.comp). Commands (x, y, z) at 16-byte strides: far horizontal, near horizontal, near
//   vertical.
//   Radius-following (ADAPTIVE): bucket k of field f (0 far, 1 near) runs 4 workgroups per entry
//   of its tile lists (tiles.comp): commands tile_list_index(f, k, pass), 0 when a list is empty.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x_id = 100, local_size_y_id = 101) in;  // as common.glsl (ComputePipeline sets them)
#include "tiles.glsl"

layout(constant_id = 0) const bool ADAPTIVE = false;
layout(constant_id = 1) const int BUCKETS = 1;

layout(push_constant) uniform Groups {
  uvec2 horizontal;  // workgroups of a full horizontal pass (fixed kernel)
  uvec2 vertical;    // workgroups of a full vertical pass (fixed kernel)
} groups;
layout(std430, binding = 2) readonly buffer TileState { uint tile_state[]; };  // see tiles.glsl

layout(std430, binding = 0) readonly buffer ChannelMax { uint max_bits[8]; uint bucket_mask[2]; };
layout(std430, binding = 1) writeonly buffer Dispatches { uvec4 dispatch[]; };

uvec4 command(bool run, uvec2 size) { return run ? uvec4(size, 1u, 0u) : uvec4(0u, 0u, 1u, 0u); }

void main() {
  if (gl_GlobalInvocationID.x != 0u || gl_GlobalInvocationID.y != 0u) return;
  if (ADAPTIVE) {
    for (int f = 0; f < 2; ++f)
      for (int k = 1; k <= BUCKETS; ++k)
        for (int pass = 0; pass < 2; ++pass) {
          const int list = tile_list_index(f, k, pass);
          const uint entries = tile_state[list];
          dispatch[list] = command(entries != 0u, uvec2(entries, 4u));
        }
  } else {
    const bool far_present = max_bits[3] != 0u, near_present = max_bits[7] != 0u;
    dispatch[0] = command(far_present, groups.horizontal);
    dispatch[1] = command(near_present, groups.horizontal);
    dispatch[2] = command(near_present, groups.vertical);
  }
}
