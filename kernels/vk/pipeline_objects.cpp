#include "pipeline_objects.hpp"

#include <stdexcept>

#include <fmt/format.h>

#include "vk_check.hpp"

namespace bokeh::vk {

void create_layouts(VkDevice device, const std::vector<VkDescriptorType>& bindings, VkShaderStageFlags stages,
                    std::uint32_t push_constant_bytes, PipelineObjects& objects) {
  std::vector<VkDescriptorSetLayoutBinding> layout_bindings;
  for (std::uint32_t i = 0; i < bindings.size(); ++i) layout_bindings.push_back({i, bindings[i], 1, stages, nullptr});
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.bindingCount = static_cast<std::uint32_t>(layout_bindings.size());
  set_info.pBindings = layout_bindings.data();
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VK_CHECK(vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout));
  objects.set_layout = {set_layout,
                        [device](VkDescriptorSetLayout l) { vkDestroyDescriptorSetLayout(device, l, nullptr); }};

  const VkPushConstantRange range{stages, 0, push_constant_bytes};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &set_layout;
  layout_info.pushConstantRangeCount = push_constant_bytes > 0 ? 1 : 0;
  layout_info.pPushConstantRanges = &range;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VK_CHECK(vkCreatePipelineLayout(device, &layout_info, nullptr, &layout));
  objects.layout = {layout, [device](VkPipelineLayout l) { vkDestroyPipelineLayout(device, l, nullptr); }};
}

Handle<VkShaderModule> create_shader_module(VkDevice device, std::span<const std::uint32_t> spirv) {
  VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  module_info.codeSize = spirv.size_bytes();
  module_info.pCode = spirv.data();
  VkShaderModule module = VK_NULL_HANDLE;
  VK_CHECK(vkCreateShaderModule(device, &module_info, nullptr, &module));
  return {module, [device](VkShaderModule m) { vkDestroyShaderModule(device, m, nullptr); }};
}

DescriptorSet::DescriptorSet(Context& ctx, VkDescriptorSetLayout layout, const std::vector<VkDescriptorType>& bindings)
    : ctx_(ctx), bindings_(bindings) {
  const VkDevice device = ctx.device();
  std::vector<VkDescriptorPoolSize> sizes;
  for (VkDescriptorType type : bindings) sizes.push_back({type, 1});
  VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pool_info.maxSets = 1;
  pool_info.poolSizeCount = static_cast<std::uint32_t>(sizes.size());
  pool_info.pPoolSizes = sizes.data();
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VK_CHECK(vkCreateDescriptorPool(device, &pool_info, nullptr, &pool));
  pool_ = {pool, [device](VkDescriptorPool p) { vkDestroyDescriptorPool(device, p, nullptr); }};

  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = pool;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &layout;
  VK_CHECK(vkAllocateDescriptorSets(device, &alloc, &set_));
}

void DescriptorSet::write(std::uint32_t binding, VkDescriptorType type, const VkDescriptorBufferInfo* buffer,
                          const VkDescriptorImageInfo* image, const VkBufferView* texel) {
  VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  write.dstSet = set_;
  write.dstBinding = binding;
  write.descriptorCount = 1;
  write.descriptorType = type;
  write.pBufferInfo = buffer;
  write.pImageInfo = image;
  write.pTexelBufferView = texel;
  vkUpdateDescriptorSets(ctx_.device(), 1, &write, 0, nullptr);
}

void DescriptorSet::bind(std::uint32_t binding, const Buffer& buffer) {
  const VkDescriptorType type = binding < bindings_.size() ? bindings_[binding] : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  if (type != VK_DESCRIPTOR_TYPE_STORAGE_BUFFER && type != VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER)
    throw std::logic_error(fmt::format("binding {} is not a buffer binding", binding));
  const VkDescriptorBufferInfo info{buffer.get(), 0, VK_WHOLE_SIZE};
  write(binding, type, &info, nullptr);
}

void DescriptorSet::bind(std::uint32_t binding, const StorageImage3D& image) {
  const VkDescriptorImageInfo info{VK_NULL_HANDLE, image.view(), VK_IMAGE_LAYOUT_GENERAL};
  write(binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, nullptr, &info);
}

void DescriptorSet::bind(std::uint32_t binding, const TexelView& view) {
  const VkBufferView v = view.get();
  write(binding, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, nullptr, nullptr, &v);
}

}  // namespace bokeh::vk
