#pragma once
// Small float vectors for the CPU references' inner loops (GCC/Clang vector extensions): 4 lanes
// (SSE2) in a portable x86-64 build, 8 (AVX) where the compiler targets it (-march=native, the
// BOKEH_NATIVE CMake option). Lane l of every operation is the scalar operation on lane l, so a loop
// that keeps each lane's order of operations gives the scalar loop's result bit for bit.
#include <cstdint>
#include <cstring>

namespace bokeh::simd {

#if defined(__AVX__)
constexpr int kWidth = 8;
#else
constexpr int kWidth = 4;
#endif
using f32v = float __attribute__((vector_size(kWidth * 4)));
using i32v = std::int32_t __attribute__((vector_size(kWidth * 4)));

inline f32v load(const float* p) {
  f32v v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline i32v load(const std::int32_t* p) {
  i32v v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(float* p, f32v v) { std::memcpy(p, &v, sizeof v); }
inline f32v splat(float x) { return f32v{} + x; }
inline i32v splat(std::int32_t x) { return i32v{} + x; }
// a where the mask lane is all ones, +0.0 where it is zero. Adding +0.0 leaves every sum that is not
// -0.0 unchanged, and a sum that starts at +0.0 never becomes -0.0 (x + -x rounds to +0.0).
inline f32v masked(f32v a, i32v mask) { return reinterpret_cast<f32v>(reinterpret_cast<i32v>(a) & mask); }

}  // namespace bokeh::simd
