#pragma once
// What compute and graphics pipelines share: the objects equal pipelines share through the context's
// cache, their layouts (storage and uniform buffers, uniform texel buffers and storage images in
// binding order, push constants), shader modules, and a descriptor set of their own.
#include <cstdint>
#include <span>
#include <vector>

#include <vulkan/vulkan.h>

#include "context.hpp"
#include "handle.hpp"
#include "memory.hpp"

namespace bokeh::vk {

// Members die in reverse order: the pipeline before its layouts and render pass.
struct PipelineObjects {
  Handle<VkRenderPass> render_pass;  // graphics pipelines only
  Handle<VkDescriptorSetLayout> set_layout;
  Handle<VkPipelineLayout> layout;
  Handle<VkPipeline> pipeline;
};

// Creates objects.set_layout and objects.layout: one descriptor per binding, and push constants of
// push_constant_bytes (none when 0), all visible to `stages`.
void create_layouts(VkDevice device, const std::vector<VkDescriptorType>& bindings, VkShaderStageFlags stages,
                    std::uint32_t push_constant_bytes, PipelineObjects& objects);

Handle<VkShaderModule> create_shader_module(VkDevice device, std::span<const std::uint32_t> spirv);

// One descriptor set from a pool of its own, for a pipeline's bindings.
class DescriptorSet {
 public:
  DescriptorSet(Context& ctx, VkDescriptorSetLayout layout, const std::vector<VkDescriptorType>& bindings);

  void bind(std::uint32_t binding, const Buffer& buffer);  // a storage or uniform buffer, as declared
  void bind(std::uint32_t binding, const StorageImage3D& image);
  void bind(std::uint32_t binding, const TexelView& view);  // a uniform texel buffer
  VkDescriptorSet get() const { return set_; }

 private:
  void write(std::uint32_t binding, VkDescriptorType type, const VkDescriptorBufferInfo* buffer,
             const VkDescriptorImageInfo* image, const VkBufferView* texel = nullptr);

  Context& ctx_;
  std::vector<VkDescriptorType> bindings_;
  Handle<VkDescriptorPool> pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
};

}  // namespace bokeh::vk
