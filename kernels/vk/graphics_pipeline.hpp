#pragma once
// A graphics pipeline drawing off-screen into a ColorTarget: one render pass (one colour attachment,
// contents loaded and stored, no clear), its framebuffer, storage buffers and push constants visible
// to the vertex and fragment shaders, and a blend mode. There are no vertex buffers: shaders build
// their primitives from gl_VertexIndex, gl_InstanceIndex and the bound buffers. Equal pipelines share
// one compiled pipeline and render pass through the context's cache, as compute pipelines do.
//
// A render pass rather than dynamic rendering: it is core Vulkan 1.0 and needs no device feature
// enabled (dynamic rendering needs Vulkan 1.3 or VK_KHR_dynamic_rendering, enabled at device creation).
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <vulkan/vulkan.h>

#include "context.hpp"
#include "handle.hpp"
#include "memory.hpp"
#include "pipeline_objects.hpp"

namespace bokeh::vk {

class GraphicsPipeline {
 public:
  // additive: every channel becomes destination + fragment (ONE, ONE, ADD), so the result does not
  // depend on the order primitives land in, up to floating-point rounding.
  enum class Blend { replace, additive };

  GraphicsPipeline(Context& ctx, const ColorTarget& target, std::span<const std::uint32_t> vertex_spirv,
                   std::span<const std::uint32_t> fragment_spirv, std::vector<VkDescriptorType> bindings,
                   std::uint32_t push_constant_bytes, Blend blend);

  void bind(std::uint32_t binding, const Buffer& buffer);

  // Waits for earlier compute and transfer writes (to `args` and the bound buffers), then draws the
  // triangle list that the VkDrawIndirectCommand at `offset` of `args` describes, inside the render
  // pass over the target's top-left width x height pixels (viewport and scissor: that rectangle).
  // The target must rest in COLOR_ATTACHMENT_OPTIMAL (as copy_to_target leaves it).
  void draw_indirect(VkCommandBuffer cmd, const void* push_constants, std::uint32_t width, std::uint32_t height,
                     const Buffer& args, VkDeviceSize offset = 0) const;

 private:
  Context& ctx_;
  std::uint32_t push_constant_bytes_;
  std::shared_ptr<PipelineObjects> shared_;
  DescriptorSet set_;
  Handle<VkFramebuffer> framebuffer_;
};

// Copies width x height texels (row-major, tightly packed, of the target's format: a vec4 per pixel
// for R32G32B32A32_SFLOAT) from `src` into the target's top-left corner, after earlier compute
// writes to `src` and draws into the target; leaves the target in COLOR_ATTACHMENT_OPTIMAL.
void copy_to_target(VkCommandBuffer cmd, const Buffer& src, const ColorTarget& target, std::uint32_t width,
                    std::uint32_t height);

// The reverse, after the draws into the target; later compute passes and transfers (downloads) see
// what it wrote to `dst`.
void copy_from_target(VkCommandBuffer cmd, const ColorTarget& target, const Buffer& dst, std::uint32_t width,
                      std::uint32_t height);

}  // namespace bokeh::vk
