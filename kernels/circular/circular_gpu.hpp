#pragma once
// The circular separable filters on the GPU (circular_gpu.cpp): passes layers, far_horizontal,
// far_vertical, near_horizontal, near_vertical; radius-following (adaptive on): layers, tiles, far,
// near.
#include <cstdint>
#include <memory>
#include <optional>

#include "circular_separable.hpp"
#include "method.hpp"

namespace bokeh {

// How the convolution passes load their inputs: two choices that help lavapipe and would cost a
// GPU, so they are explicit (specialisation constants TEXEL_LOADS and SLIDING_WINDOW of
// shaders/circular/convolution.glsl; circular_gpu.cpp says why). Every shape gives bit-identical
// output.
struct CircularPassShape {
  bool texel_loads = false;     // inputs through uniform texel buffers instead of storage buffers
  bool sliding_window = false;  // one input and one kernel tap load per tap, OUTPUTS inputs in registers
};
// Both on for CPU devices (lavapipe), both off for GPUs.
CircularPassShape circular_pass_shape_for(const vk::DeviceInfo& device);

// `components` (1..6) far-field components; the rest as circular_config(options, components) reads
// them (near_components, precision, adaptive, disc radius options.pattern.max_radius_px()). shape:
// the device's own unless given.
std::unique_ptr<gpu::GpuFilter> make_circular_gpu(gpu::GpuFrame& frame, const FilterOptions& options, int components,
                                                  std::optional<CircularPassShape> shape = std::nullopt);

// Bytes of one component's intermediate per pixel (RGBA layers), as the GPU stores it.
std::uint64_t circular_component_bytes_per_pixel(IntermediatePrecision precision);

// Bytes of the radius-following mode's bucket table (uniform; layers.comp and tiles.comp): the
// ramps and the tile reach of up to 32 buckets.
inline constexpr std::uint64_t kCircularBucketTableBytes = 2 * 32 * 16;

// Bytes of the uniform buffer holding one kernel (weights, bracketing, taps) on the GPU; must fit
// the device's maxUniformBufferRange (64 KiB on lavapipe and NVIDIA: a kernel of up to 680 taps a
// component at 6 components).
std::uint64_t circular_kernel_block_bytes(const CircularKernel& kernel);

}  // namespace bokeh
