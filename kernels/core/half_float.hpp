#pragma once
// Float -> half -> float rounding (to nearest, ties to even, as Imath::half and an RGBA16F target
// that rounds to nearest), for the CPU references' f16 storage. With F16C it converts eight values
// per instruction: compiled in where the compiler targets F16C (-march=native on such a CPU, CMake
// option BOKEH_NATIVE), else chosen at run time on x86-64 CPUs that have it; Imath's software
// conversion otherwise. Every path gives the same bits (tests/kernels/flag/test_flag_buffers.cpp).
#include <cstddef>
#include <string>

namespace bokeh {

// values[i] = float(half(values[i])) for i < count.
void round_to_half(float* values, std::size_t count);
float round_to_half(float value);
// The same through Imath's software conversion only: the reference the F16C paths are tested against.
void round_to_half_software(float* values, std::size_t count);

// "f16c (compiled in)", "f16c (run-time dispatch)" or "software (Imath)": what round_to_half uses here.
std::string half_conversion();

}  // namespace bokeh
