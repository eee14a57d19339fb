// Shared by horizontal.comp and vertical.comp (kernels/gaussian/gaussian_method.cpp says why each
// choice, and which devices take it). Included after common.glsl.
layout(constant_id = 0) const int RADIUS = 1;      // taps -R..R
layout(constant_id = 1) const int OUTPUTS = 1;     // output pixels per invocation along the pass
// Input through a uniform texel buffer (texelFetch: one vector gather on lavapipe) rather than a
// storage buffer (a per-lane loop of scalar loads there); GPUs keep the storage-buffer loads.
layout(constant_id = 2) const bool TEXEL_LOADS = false;

const int TAPS = 2 * RADIUS + 1;

// The normalised taps, four to a vec4 (std140), read at a loop-uniform index: plain loads on
// lavapipe, the constant cache on GPUs.
layout(std140, binding = 0) uniform Taps { vec4 taps4[(TAPS + 3) / 4]; };
float tap(int i) { return taps4[i >> 2][i & 3]; }

// Every output sums its taps i = 0..TAPS-1 in order, as the CPU reference does. The OUTPUTS inputs
// that tap i needs (input index first + k + i - R for output k) stay in a window that shifts by one
// per tap, so each tap loads one input whatever OUTPUTS is.
#define GAUSSIAN_SUMS(sum, load, first, last)                                         \
  vec3 sum[OUTPUTS];                                                                  \
  {                                                                                   \
    vec3 window[OUTPUTS];                                                             \
    for (int k = 0; k < OUTPUTS; ++k) sum[k] = vec3(0.0);                             \
    for (int k = 1; k < OUTPUTS; ++k) window[k] = load(clamp(first + k - 1 - RADIUS, 0, last)); \
    for (int i = 0; i < TAPS; ++i) {                                                  \
      for (int k = 0; k < OUTPUTS - 1; ++k) window[k] = window[k + 1];                \
      window[OUTPUTS - 1] = load(clamp(first + i + OUTPUTS - 1 - RADIUS, 0, last));   \
      const float w = tap(i);                                                         \
      for (int k = 0; k < OUTPUTS; ++k) sum[k] += w * window[k];                      \
    }                                                                                 \
  }
