#version 450
// Circular separable filter, horizontal pass: for every component c, the complex response
// H_c(x, y) = sum_i F_c(i) J(x + i, y) of each RGBA channel of the layer (borders clamp), stored at
// the intermediate precision. bracketed10 convolves with Garcia's bracketed kernels G' = (G - O) / S
// (>= 0, summing to 1) so I' lies in [0, M], stores the 10-bit code of I' / M, and stores the box sum
// sum(J) / M as half for the vertical pass to undo the bracketing. Mirrors horizontal_pass() in
// kernels/circular/circular_separable.cpp operation for operation.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "convolution.glsl"

layout(binding = 10) uniform samplerBuffer layer_texels;  // the layer again, read when TEXEL_LOADS
layout(std430, binding = 11) readonly restrict buffer TileLists { uint tile_list[]; };  // buckets: tiles.glsl

#if PRECISION == 2
#define TAP_RE t.z  // G'_re
#define TAP_IM t.w  // G'_im
#else
#define TAP_RE t.x  // Re F
#define TAP_IM t.y  // Im F
#endif

// J(x, y) of this row, x clamped to the image; for a bucket, the layer's share in it (as
// circular_blur_adaptive: the hat weight times (rgb, 1)).
vec4 load_layer(uint row, int x) {
  const uint i = row + uint(clamp(x, 0, params.width_px - 1));
  const vec4 v = TEXEL_LOADS ? texelFetch(layer_texels, int(i)) : layer[i];
  if (BUCKET == 0) return v;
  return vec4(v.rgb, 1.0) * max(0.0, 1.0 - abs(v.a - float(BUCKET)));
}

void main() {
  // This invocation computes OUTPUTS pixels along row y from column x0: each layer value it loads
  // serves up to OUTPUTS taps. Per output pixel the sum runs over i = 0..TAPS-1 in order.
  int x0 = int(gl_GlobalInvocationID.x) * OUTPUTS, y = int(gl_GlobalInvocationID.y);
  bool zero = false;  // a tile whose response is 0 but which the vertical pass reads: store zeros
  if (BUCKET > 0) {
    const uint entry = TILE_ENTRY(0);
    const ivec2 origin = tile_origin(entry);
    x0 = origin.x + int(gl_LocalInvocationID.x) * OUTPUTS;
    y = origin.y + int(gl_WorkGroupID.y * gl_WorkGroupSize.y + gl_LocalInvocationID.y);
    zero = (entry & ZERO_TILE) != 0u;
  }
  if (x0 >= params.width_px || y >= params.height_px) return;
  const uint row = uint(y * params.width_px);
#define DECLARE(c, buf)                                     \
  vec4 re##c[OUTPUTS], im##c[OUTPUTS];                      \
  for (int k = 0; k < OUTPUTS; ++k) re##c[k] = vec4(0.0), im##c[k] = vec4(0.0);
  FOR_EACH_COMPONENT(DECLARE)
  vec4 box[OUTPUTS];
  for (int k = 0; k < OUTPUTS; ++k) box[k] = vec4(0.0);
  // Adds tap i times the layer value j to output k.
#define ACCUMULATE(c, buf)                     \
  if (c < COMPONENTS) {                        \
    const vec4 t = kernel.taps[c * TAPS + i];  \
    re##c[k] += TAP_RE * j;                    \
    im##c[k] += TAP_IM * j;                    \
  }
  if (zero) {
    // The accumulators stay 0.
  } else if (SLIDING_WINDOW) {
    // window[k] = J(x0 + k + i - R), the value output k takes at tap i: one new load per tap.
    vec4 window[OUTPUTS];
    for (int k = 1; k < OUTPUTS; ++k) window[k] = load_layer(row, x0 + k - 1 - RADIUS);
    for (int i = 0; i < TAPS; ++i) {
      for (int k = 0; k < OUTPUTS - 1; ++k) window[k] = window[k + 1];
      window[OUTPUTS - 1] = load_layer(row, x0 + i + OUTPUTS - 1 - RADIUS);
      for (int k = 0; k < OUTPUTS; ++k) {
        const vec4 j = window[k];
        FOR_EACH_COMPONENT(ACCUMULATE)
        if (PRECISION == 2) box[k] += j;
      }
    }
  } else {
    // Value x0 + s - R serves tap i = s - k of output k.
    for (int s = 0; s < TAPS + OUTPUTS - 1; ++s) {
      const vec4 j = load_layer(row, x0 + s - RADIUS);
      for (int k = 0; k < OUTPUTS; ++k) {
        const int i = s - k;
        if (i < 0 || i >= TAPS) continue;
        FOR_EACH_COMPONENT(ACCUMULATE)
        if (PRECISION == 2) box[k] += j;
      }
    }
  }
#if PRECISION == 0
#define STORE(c, buf)                   \
  if (c < COMPONENTS) {                 \
    buf.d[2u * pixel] = re##c[k];       \
    buf.d[2u * pixel + 1u] = im##c[k];  \
  }
#elif PRECISION == 1
#define STORE(c, buf)                                                                                    \
  if (c < COMPONENTS)                                                                                    \
    buf.d[pixel] = uvec4(packHalf2x16(re##c[k].rg), packHalf2x16(re##c[k].ba), packHalf2x16(im##c[k].rg), \
                         packHalf2x16(im##c[k].ba));
#else
  const vec4 m = channel_max();
  const vec4 inv_max = vec4(m.x > 0.0 ? 1.0 / m.x : 0.0, m.y > 0.0 ? 1.0 / m.y : 0.0, m.z > 0.0 ? 1.0 / m.z : 0.0,
                            m.w > 0.0 ? 1.0 / m.w : 0.0);
  // As the CPU: nearbyint (round half to even) of clamp(I' / M, 0, 1) * 1023.
#define STORE(c, buf)                                                                           \
  if (c < COMPONENTS) {                                                                         \
    const uvec4 code_re = uvec4(roundEven(clamp(re##c[k] * inv_max, 0.0, 1.0) * UNORM10_MAX));  \
    const uvec4 code_im = uvec4(roundEven(clamp(im##c[k] * inv_max, 0.0, 1.0) * UNORM10_MAX));  \
    buf.d[3u * pixel] = pack_unorm10x3(code_re.rgb);                                            \
    buf.d[3u * pixel + 1u] = pack_unorm10x3(uvec3(code_re.a, code_im.rg));                      \
    buf.d[3u * pixel + 2u] = pack_unorm10x3(uvec3(code_im.ba, 0u));                             \
  }
#endif
  for (int k = 0; k < OUTPUTS; ++k) {
    if (x0 + k >= params.width_px) break;
    const uint pixel = row + uint(x0 + k);
#if PRECISION == 2
    const vec4 b = box[k] * inv_max;
    box_over_max[pixel] = uvec2(packHalf2x16(b.rg), packHalf2x16(b.ba));
#endif
    FOR_EACH_COMPONENT(STORE)
  }
}
