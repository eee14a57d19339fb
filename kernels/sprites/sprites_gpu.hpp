#pragma once
#include <cstdint>
#include <memory>

#include "method.hpp"
#include "sprites.hpp"

namespace bokeh {

// Passes: detect (compute: contrast test, append with an atomic counter that is also the indirect
// draw's instance count, colour removed from the gather input), gather (naive's GPU gather of the
// rest), sprites (copy of the gather into an off-screen RGBA32F colour target, one vkCmdDrawIndirect
// of the sprite quads with additive blending, copy back into the frame's output).
std::unique_ptr<gpu::GpuFilter> make_sprites_gpu(gpu::GpuFrame& frame, const FilterOptions& options,
                                                 const SpriteSettings& settings);

// Mirrors `Counters` in shaders/sprites/detect.comp: the indirect draw's arguments first.
struct SpriteCounters {
  VkDrawIndirectCommand draw;
  std::uint32_t overflowed;
  std::uint32_t quad_pixels_low, quad_pixels_high;  // a 64-bit count: frames can rasterise over 2^32 pixels
};

// The colour target's format: f32 like the frame's buffers, so the copies are plain texel copies.
constexpr VkFormat kSpriteTargetFormat = VK_FORMAT_R32G32B32A32_SFLOAT;

}  // namespace bokeh
