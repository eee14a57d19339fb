#include "half_float.hpp"

#include <Imath/half.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define BOKEH_X86_F16C_DISPATCH 1
#endif

namespace bokeh {

void round_to_half_software(float* values, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) values[i] = static_cast<float>(Imath::half(values[i]));
}

namespace {

#if defined(BOKEH_X86_F16C_DISPATCH)
#if defined(__F16C__) && defined(__AVX__)
#define BOKEH_F16C_TARGET
#else
#define BOKEH_F16C_TARGET __attribute__((target("avx,f16c")))
#endif
// _MM_FROUND_TO_NEAREST_INT: round to nearest even whatever MXCSR says, as Imath does.
BOKEH_F16C_TARGET void round_to_half_f16c(float* values, std::size_t count) {
  constexpr int kNearest = _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC;
  std::size_t i = 0;
  for (; i + 8 <= count; i += 8)
    _mm256_storeu_ps(values + i, _mm256_cvtph_ps(_mm256_cvtps_ph(_mm256_loadu_ps(values + i), kNearest)));
  for (; i < count; ++i)
    values[i] = _mm_cvtss_f32(_mm_cvtph_ps(_mm_cvtps_ph(_mm_set_ss(values[i]), kNearest)));
}

bool cpu_has_f16c() {
#if defined(__F16C__) && defined(__AVX__)
  return true;
#else
  static const bool has = __builtin_cpu_supports("f16c") && __builtin_cpu_supports("avx");
  return has;
#endif
}
#endif

}  // namespace

void round_to_half(float* values, std::size_t count) {
#if defined(BOKEH_X86_F16C_DISPATCH)
  if (cpu_has_f16c()) return round_to_half_f16c(values, count);
#endif
  round_to_half_software(values, count);
}

float round_to_half(float value) {
  round_to_half(&value, 1);
  return value;
}

std::string half_conversion() {
#if defined(BOKEH_X86_F16C_DISPATCH)
#if defined(__F16C__) && defined(__AVX__)
  return "f16c (compiled in)";
#else
  return cpu_has_f16c() ? "f16c (run-time dispatch)" : "software (Imath)";
#endif
#else
  return "software (Imath)";
#endif
}

}  // namespace bokeh
