#version 450
// Circular separable filter, after layers.comp: the indirect dispatch sizes of the passes that an
// empty field (alpha max 0) can skip. An empty field's horizontal pass, and the near vertical pass,
// get no workgroups; the far vertical pass always runs (it writes the output) and skips its own
// convolution (vertical.comp). Decided on the GPU, so a frame needs no read-back. One invocation.
layout(local_size_x_id = 100, local_size_y_id = 101) in;  // as common.glsl (ComputePipeline sets them)

layout(push_constant) uniform Groups {
  uvec2 horizontal;  // workgroups of a full horizontal pass
  uvec2 vertical;    // workgroups of a full vertical pass
} groups;

layout(std430, binding = 0) readonly buffer ChannelMax { uint max_bits[8]; };
// VkDispatchIndirectCommand (x, y, z) at 16-byte strides: far horizontal, near horizontal, near vertical.
layout(std430, binding = 1) writeonly buffer Dispatches { uvec4 dispatch[3]; };

void main() {
  if (gl_GlobalInvocationID.x != 0u || gl_GlobalInvocationID.y != 0u) return;
  const bool far_present = max_bits[3] != 0u, near_present = max_bits[7] != 0u;
  dispatch[0] = far_present ? uvec4(groups.horizontal, 1u, 0u) : uvec4(0u, 0u, 1u, 0u);
  dispatch[1] = near_present ? uvec4(groups.horizontal, 1u, 0u) : uvec4(0u, 0u, 1u, 0u);
  dispatch[2] = near_present ? uvec4(groups.vertical, 1u, 0u) : uvec4(0u, 0u, 1u, 0u);
}
