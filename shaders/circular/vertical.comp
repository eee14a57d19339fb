#version 450
// Circular separable filter, vertical pass and composite. Per component, V_c = sum_j F_c(j) H_c(x, y + j)
// (complex products, borders clamp); the blurred layer is b = sum_c A_c Re V_c + B_c Im V_c (A, B
// already divided by the kernel's normalisation). Then, as circular_blur() on the CPU:
//   LAYER 0 (far, runs first): out = sharp colour; where the pixel's own far alpha a > 0 and
//     b.a > 1e-4, out = (1 - a) sharp + a b.rgb / b.a. Writes every output pixel.
//   LAYER 1 (near, runs last): alpha = clamp(b.a, 0, 1); where alpha > 0,
//     out = (1 - alpha) out + b.rgb (alpha / b.a), over the far pass's output.
// bracketed10 undoes Garcia's bracketing on load: H = S (code / 1023 M) + O (sum(J) / M) M.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "convolution.glsl"

layout(std430, binding = 10) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 11) buffer Out { vec4 result[]; };

const float MIN_FAR_ALPHA = 1e-4;  // kMinFarAlpha in kernels/circular_separable.cpp

// H_c at `pixel` from component buffer `buf` into vec4 re, im.
#if PRECISION == 0
#define LOAD_COMPLEX(c, buf, pixel)        \
  const vec4 h_re = buf.d[2u * pixel];     \
  const vec4 h_im = buf.d[2u * pixel + 1u];
#elif PRECISION == 1
#define LOAD_COMPLEX(c, buf, pixel)                                                  \
  const uvec4 w = buf.d[pixel];                                                      \
  const vec4 h_re = vec4(unpackHalf2x16(w.x), unpackHalf2x16(w.y));                  \
  const vec4 h_im = vec4(unpackHalf2x16(w.z), unpackHalf2x16(w.w));
#else
// I = S (code / 1023 M) + O (sum(J) / M) M, as Intermediate::load on the CPU.
#define LOAD_COMPLEX(c, buf, pixel)                                              \
  const uvec3 w0 = unpack_unorm10x3(buf.d[3u * pixel]);                          \
  const uvec3 w1 = unpack_unorm10x3(buf.d[3u * pixel + 1u]);                     \
  const uvec3 w2 = unpack_unorm10x3(buf.d[3u * pixel + 2u]);                     \
  const vec4 code_re = vec4(w0, w1.x), code_im = vec4(w1.yz, w2.xy);             \
  const vec4 k = kernel.bracket[c]; /* (O_re, S_re, O_im, S_im) */               \
  const vec4 h_re = k.y * (code_re / UNORM10_MAX * m) + k.x * box;               \
  const vec4 h_im = k.w * (code_im / UNORM10_MAX * m) + k.z * box;
#endif

void main() {
  // This invocation computes OUTPUTS pixels down column x from row y0: each H value it loads serves up
  // to OUTPUTS taps. Per output pixel the sum still runs over j = 0..TAPS-1 in order, as on the CPU.
  const int x = int(gl_GlobalInvocationID.x), y0 = int(gl_GlobalInvocationID.y) * OUTPUTS;
  if (x >= params.width_px || y0 >= params.height_px) return;
#if PRECISION == 2
  const vec4 m = channel_max();
#endif
#define DECLARE(c, buf)                                            \
  vec4 acc_re##c[OUTPUTS], acc_im##c[OUTPUTS];                     \
  for (int k = 0; k < OUTPUTS; ++k) acc_re##c[k] = vec4(0.0), acc_im##c[k] = vec4(0.0);
  FOR_EACH_COMPONENT(DECLARE)
  for (int s = 0; s < TAPS + OUTPUTS - 1; ++s) {
    const int sy = clamp(y0 + s - RADIUS, 0, params.height_px - 1);
    const uint source = uint(sy * params.width_px + x);
#if PRECISION == 2
    const uvec2 bw = box_over_max[source];
    const vec4 box = vec4(unpackHalf2x16(bw.x), unpackHalf2x16(bw.y)) * m;
#endif
#define ACCUMULATE(c, buf)                                 \
  if (c < COMPONENTS) {                                    \
    LOAD_COMPLEX(c, buf, source)                           \
    for (int k = 0; k < OUTPUTS; ++k) {                    \
      const int j = s - k; /* tap index for output y0 + k */ \
      if (j >= 0 && j < TAPS) {                            \
        const vec2 t = kernel.taps[c * TAPS + j].xy;       \
        acc_re##c[k] += t.x * h_re - t.y * h_im;           \
        acc_im##c[k] += t.x * h_im + t.y * h_re;           \
      }                                                    \
    }                                                      \
  }
    FOR_EACH_COMPONENT(ACCUMULATE)
  }
  for (int k = 0; k < OUTPUTS; ++k) {
    const int y = y0 + k;
    if (y >= params.height_px) break;
    vec4 b = vec4(0.0);
#define COMBINE(c, buf) \
  if (c < COMPONENTS) b += kernel.weight[c].x * acc_re##c[k] + kernel.weight[c].y * acc_im##c[k];
    FOR_EACH_COMPONENT(COMBINE)

    const uint i = uint(y * params.width_px + x);
    if (LAYER == 0) {
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
