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
#include "circular_common.glsl"

layout(std430, binding = 10) readonly buffer Color { vec4 color[]; };
layout(std430, binding = 11) buffer Out { vec4 result[]; };

const float MIN_FAR_ALPHA = 1e-4;  // kMinFarAlpha in kernels/circular_separable.cpp

void load_complex(int c, uint pixel, out vec4 re, out vec4 im) {
#if PRECISION == 0
  re = load_inter(c, 2u * pixel);
  im = load_inter(c, 2u * pixel + 1u);
#elif PRECISION == 1
  const uvec4 w = load_inter(c, pixel);
  re = vec4(unpackHalf2x16(w.x), unpackHalf2x16(w.y));
  im = vec4(unpackHalf2x16(w.z), unpackHalf2x16(w.w));
#else
  const uvec3 a = unpack_unorm10x3(load_inter(c, 3u * pixel));
  const uvec3 b = unpack_unorm10x3(load_inter(c, 3u * pixel + 1u));
  const uvec3 d = unpack_unorm10x3(load_inter(c, 3u * pixel + 2u));
  const vec4 code_re = vec4(a, b.x), code_im = vec4(b.yz, d.xy);
  const vec4 m = channel_max();
  const uvec2 bw = box_over_max[pixel];
  const vec4 box = vec4(unpackHalf2x16(bw.x), unpackHalf2x16(bw.y)) * m;
  const vec4 k = kernel.bracket[c];  // (O_re, S_re, O_im, S_im)
  re = k.y * (code_re / UNORM10_MAX * m) + k.x * box;
  im = k.w * (code_im / UNORM10_MAX * m) + k.z * box;
#endif
}

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (outside(p)) return;
  vec4 acc_re[COMPONENTS], acc_im[COMPONENTS];
  for (int c = 0; c < COMPONENTS; ++c) acc_re[c] = vec4(0.0), acc_im[c] = vec4(0.0);
  for (int j = 0; j < TAPS; ++j) {
    const int sy = clamp(p.y + j - RADIUS, 0, params.height_px - 1);
    const uint source = uint(sy * params.width_px + p.x);
    for (int c = 0; c < COMPONENTS; ++c) {
      const vec2 t = kernel.taps[c * TAPS + j].xy;
      vec4 h_re, h_im;
      load_complex(c, source, h_re, h_im);
      acc_re[c] += t.x * h_re - t.y * h_im;
      acc_im[c] += t.x * h_im + t.y * h_re;
    }
  }
  vec4 b = vec4(0.0);
  for (int c = 0; c < COMPONENTS; ++c) b += kernel.weight[c].x * acc_re[c] + kernel.weight[c].y * acc_im[c];

  const uint i = index_of(p);
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
