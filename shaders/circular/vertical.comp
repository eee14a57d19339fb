#version 450
// Circular separable filter, vertical pass and composite (for a bucket of the radius-following
// filter: the vertical pass, added to the field's sum over its tiles; composite.comp composites).
// Per component, V_c = sum_j F_c(j) H_c(x, y + j) (complex products, borders clamp); the blurred
// layer is b = sum_c A_c Re V_c + B_c Im V_c (A, B already divided by the kernel's normalisation).
// Then, as circular_blur() on the CPU:
//   LAYER 0 (far, runs first): out = sharp colour; where the pixel's own far alpha a > 0 and
//     b.a > 1e-4, out = (1 - a) sharp + a b.rgb / b.a. Writes every output pixel.
//   LAYER 1 (near, runs last): alpha = clamp(b.a, 0, 1); where alpha > 0,
//     out = (1 - alpha) out + b.rgb (alpha / b.a), over the far pass's output.
// An empty field (alpha max 0) skips the convolution: its horizontal pass did not run (plan.comp),
// and the far composite then keeps the sharp colour everywhere (a = 0).
// bracketed10 undoes Garcia's bracketing on load: H = S (code / 1023 M) + O (sum(J) / M) M.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "convolution.glsl"

layout(std430, binding = 10) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 11) buffer Out { vec4 result[]; };
// The intermediates and box sums again, read when TEXEL_LOADS: f32 as RGBA32F (two texels a
// pixel), f16 as RGBA32UI, bracketed10 as R32UI (three texels a pixel); box sums as RG32UI.
#if PRECISION == 0
#define TEXELS samplerBuffer
#else
#define TEXELS usamplerBuffer
#endif
layout(binding = 12) uniform TEXELS inter_texels0;
layout(binding = 13) uniform TEXELS inter_texels1;
layout(binding = 14) uniform TEXELS inter_texels2;
layout(binding = 15) uniform TEXELS inter_texels3;
layout(binding = 16) uniform TEXELS inter_texels4;
layout(binding = 17) uniform TEXELS inter_texels5;
layout(binding = 18) uniform usamplerBuffer box_texels;
layout(std430, binding = 19) buffer Sum { vec4 field_sum[]; };  // BUCKET >= 1: the field's sum over buckets
layout(std430, binding = 20) readonly restrict buffer TileLists { uint tile_list[]; };  // buckets: tiles.glsl

const float MIN_FAR_ALPHA = 1e-4;  // kMinFarAlpha in kernels/circular/circular_separable.cpp

// The stored word(s) of component c at index i of its buffer.
#define FETCH(c, buf, i) (TEXEL_LOADS ? texelFetch(inter_texels##c, int(i)) : buf.d[i])
#define FETCH_UINT(c, buf, i) (TEXEL_LOADS ? texelFetch(inter_texels##c, int(i)).x : buf.d[i])

// H_c at `pixel` from component buffer `buf` into vec4 h_re, h_im.
#if PRECISION == 0
#define LOAD_COMPLEX(c, buf, pixel)             \
  const vec4 h_re = FETCH(c, buf, 2u * pixel);  \
  const vec4 h_im = FETCH(c, buf, 2u * pixel + 1u);
#elif PRECISION == 1
#define LOAD_COMPLEX(c, buf, pixel)                                  \
  const uvec4 w = FETCH(c, buf, pixel);                              \
  const vec4 h_re = vec4(unpackHalf2x16(w.x), unpackHalf2x16(w.y));  \
  const vec4 h_im = vec4(unpackHalf2x16(w.z), unpackHalf2x16(w.w));
#else
// I = S (code / 1023 M) + O (sum(J) / M) M, as horizontal_pass() on the CPU decodes it.
#define LOAD_COMPLEX(c, buf, pixel)                                      \
  const uvec3 w0 = unpack_unorm10x3(FETCH_UINT(c, buf, 3u * pixel));     \
  const uvec3 w1 = unpack_unorm10x3(FETCH_UINT(c, buf, 3u * pixel + 1u)); \
  const uvec3 w2 = unpack_unorm10x3(FETCH_UINT(c, buf, 3u * pixel + 2u)); \
  const vec4 code_re = vec4(w0, w1.x), code_im = vec4(w1.yz, w2.xy);     \
  const vec4 br = kernel.bracket[c]; /* (O_re, S_re, O_im, S_im) */      \
  const vec4 h_re = br.y * (code_re / UNORM10_MAX * m) + br.x * box;     \
  const vec4 h_im = br.w * (code_im / UNORM10_MAX * m) + br.z * box;
#endif

// The box sum sum(J) at `source` (bracketed10; 0 otherwise, unused).
vec4 load_box(uint source, vec4 m) {
#if PRECISION == 2
  const uvec2 w = TEXEL_LOADS ? texelFetch(box_texels, int(source)).xy : box_over_max[source];
  return vec4(unpackHalf2x16(w.x), unpackHalf2x16(w.y)) * m;
#else
  return vec4(0.0);
#endif
}

void main() {
  // This invocation computes OUTPUTS pixels down column x from row y0: each H value it loads serves up
  // to OUTPUTS taps. Per output pixel the sum runs over j = 0..TAPS-1 in order, as on the CPU.
  int x = int(gl_GlobalInvocationID.x), y0 = int(gl_GlobalInvocationID.y) * OUTPUTS;
  if (BUCKET > 0) {
    const ivec2 origin = tile_origin(TILE_ENTRY(1));
    x = origin.x + int(gl_WorkGroupID.y * gl_WorkGroupSize.x + gl_LocalInvocationID.x);
    y0 = origin.y + int(gl_LocalInvocationID.y) * OUTPUTS;
  }
  if (x >= params.width_px || y0 >= params.height_px) return;
  const vec4 m = PRECISION == 2 ? channel_max() : vec4(0.0);
#define DECLARE(c, buf)                                            \
  vec4 acc_re##c[OUTPUTS], acc_im##c[OUTPUTS];                     \
  for (int k = 0; k < OUTPUTS; ++k) acc_re##c[k] = vec4(0.0), acc_im##c[k] = vec4(0.0);
  FOR_EACH_COMPONENT(DECLARE)
  // Row sy of the intermediates, clamped to the image.
#define SOURCE(row) uint(clamp(row, 0, params.height_px - 1) * params.width_px + x)
  const bool field_present = max_bits[4 * field() + 3] != 0u;
  if (field_present && SLIDING_WINDOW) {
    // window_re/im##c[k] = H_c(x, y0 + k + j - R), the value output k takes at tap j.
#define DECLARE_WINDOW(c, buf) vec4 window_re##c[OUTPUTS], window_im##c[OUTPUTS];
    FOR_EACH_COMPONENT(DECLARE_WINDOW)
#define LOAD_WINDOW(c, buf, k)       \
  if (c < COMPONENTS) {              \
    LOAD_COMPLEX(c, buf, source)     \
    window_re##c[k] = h_re;          \
    window_im##c[k] = h_im;          \
  }
#define LOAD_FIRST(c, buf) LOAD_WINDOW(c, buf, k)
#define SHIFT_WINDOW(c, buf)                   \
  if (c < COMPONENTS)                          \
    for (int k = 0; k < OUTPUTS - 1; ++k)      \
      window_re##c[k] = window_re##c[k + 1], window_im##c[k] = window_im##c[k + 1];
#define LOAD_LAST(c, buf) LOAD_WINDOW(c, buf, OUTPUTS - 1)
#define ACCUMULATE_WINDOW(c, buf)                                                 \
  if (c < COMPONENTS) {                                                           \
    const vec2 t = kernel.taps[c * TAPS + j].xy;                                  \
    for (int k = 0; k < OUTPUTS; ++k) {                                           \
      acc_re##c[k] += t.x * window_re##c[k] - t.y * window_im##c[k];              \
      acc_im##c[k] += t.x * window_im##c[k] + t.y * window_re##c[k];              \
    }                                                                             \
  }
    for (int k = 1; k < OUTPUTS; ++k) {
      const uint source = SOURCE(y0 + k - 1 - RADIUS);
      const vec4 box = load_box(source, m);
      FOR_EACH_COMPONENT(LOAD_FIRST)
    }
    for (int j = 0; j < TAPS; ++j) {
      const uint source = SOURCE(y0 + j + OUTPUTS - 1 - RADIUS);
      const vec4 box = load_box(source, m);
      FOR_EACH_COMPONENT(SHIFT_WINDOW)
      FOR_EACH_COMPONENT(LOAD_LAST)
      FOR_EACH_COMPONENT(ACCUMULATE_WINDOW)
    }
  } else if (field_present) {
    // Row y0 + s - R serves tap j = s - k of output k.
#define ACCUMULATE(c, buf)                                   \
  if (c < COMPONENTS) {                                      \
    LOAD_COMPLEX(c, buf, source)                             \
    for (int k = 0; k < OUTPUTS; ++k) {                      \
      const int j = s - k;                                   \
      if (j >= 0 && j < TAPS) {                              \
        const vec2 t = kernel.taps[c * TAPS + j].xy;         \
        acc_re##c[k] += t.x * h_re - t.y * h_im;             \
        acc_im##c[k] += t.x * h_im + t.y * h_re;             \
      }                                                      \
    }                                                        \
  }
    for (int s = 0; s < TAPS + OUTPUTS - 1; ++s) {
      const uint source = SOURCE(y0 + s - RADIUS);
      const vec4 box = load_box(source, m);
      FOR_EACH_COMPONENT(ACCUMULATE)
    }
  }
  for (int k = 0; k < OUTPUTS; ++k) {
    const int y = y0 + k;
    if (y >= params.height_px) break;
    vec4 b = vec4(0.0);
#define COMBINE(c, buf) \
  if (c < COMPONENTS) b += kernel.weight[c].x * acc_re##c[k] + kernel.weight[c].y * acc_im##c[k];
    FOR_EACH_COMPONENT(COMBINE)

    const uint i = uint(y * params.width_px + x);
    if (BUCKET > 0) {
      field_sum[i] += b;  // buckets in ascending order, as the CPU sums them
    } else if (LAYER == 0) {
      vec3 o = color[i].rgb;
      const float a = layer[i].a;
      if (a > 0.0 && b.a > MIN_FAR_ALPHA) o = (1.0 - a) * o + a * b.rgb / b.a;
      result[i] = vec4(o, 1.0);
    } else {
      vec3 o = result[i].rgb;
      const float alpha = clamp(b.a, 0.0, 1.0);
      if (alpha > 0.0) o = (1.0 - alpha) * o + b.rgb * (alpha / b.a);
      result[i] = vec4(o, 1.0);
    }
  }
}
