#version 450
// Circular separable filter, horizontal pass: for every component c, the complex response
// H_c(x, y) = sum_i F_c(i) J(x + i, y) of each RGBA channel of the layer (borders clamp), stored at
// the intermediate precision. bracketed10 convolves with Garcia's bracketed kernels G' = (G - O) / S
// (>= 0, summing to 1) so I' lies in [0, M], stores the 10-bit code of I' / M, and stores the box sum
// sum(J) / M as half for the vertical pass to undo the bracketing. Mirrors horizontal_pass() in
// kernels/circular_separable.cpp operation for operation.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "circular_common.glsl"

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  const uint row = uint(p.y * params.width_px);
  vec4 re[COMPONENTS], im[COMPONENTS];
  for (int c = 0; c < COMPONENTS; ++c) re[c] = vec4(0.0), im[c] = vec4(0.0);
  vec4 box = vec4(0.0);
  for (int i = 0; i < TAPS; ++i) {
    const vec4 j = layer[row + uint(clamp(p.x + i - RADIUS, 0, params.width_px - 1))];
    for (int c = 0; c < COMPONENTS; ++c) {
      const vec4 t = kernel.taps[c * TAPS + i];
#if PRECISION == 2
      re[c] += t.z * j;
      im[c] += t.w * j;
#else
      re[c] += t.x * j;
      im[c] += t.y * j;
#endif
    }
#if PRECISION == 2
    box += j;
#endif
  }
  const uint pixel = index_of(p);
  for (int c = 0; c < COMPONENTS; ++c) {
#if PRECISION == 0
    store_inter(c, 2u * pixel, re[c]);
    store_inter(c, 2u * pixel + 1u, im[c]);
#elif PRECISION == 1
    store_inter(c, pixel, uvec4(packHalf2x16(re[c].rg), packHalf2x16(re[c].ba), packHalf2x16(im[c].rg),
                                packHalf2x16(im[c].ba)));
#else
    const vec4 m = channel_max();
    const vec4 inv_max = vec4(m.x > 0.0 ? 1.0 / m.x : 0.0, m.y > 0.0 ? 1.0 / m.y : 0.0,
                              m.z > 0.0 ? 1.0 / m.z : 0.0, m.w > 0.0 ? 1.0 / m.w : 0.0);
    // As the CPU: nearbyint (round half to even) of clamp(I' / M, 0, 1) * 1023.
    const uvec4 code_re = uvec4(roundEven(clamp(re[c] * inv_max, 0.0, 1.0) * UNORM10_MAX));
    const uvec4 code_im = uvec4(roundEven(clamp(im[c] * inv_max, 0.0, 1.0) * UNORM10_MAX));
    store_inter(c, 3u * pixel, pack_unorm10x3(code_re.rgb));
    store_inter(c, 3u * pixel + 1u, pack_unorm10x3(uvec3(code_re.a, code_im.rg)));
    store_inter(c, 3u * pixel + 2u, pack_unorm10x3(uvec3(code_im.ba, 0u)));
    if (c == 0) {
      const vec4 b = box * inv_max;
      box_over_max[pixel] = uvec2(packHalf2x16(b.rg), packHalf2x16(b.ba));
    }
#endif
  }
}
