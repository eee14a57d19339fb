#include "compute_pipeline.hpp"

#include <stdexcept>

#include <fmt/format.h>

#include "vk_check.hpp"

namespace bokeh::vk {

namespace {

// Every shader declares local_size_x_id = 100 and local_size_y_id = 101 so the host knows them.
constexpr std::uint32_t kLocalSizeXId = 100, kLocalSizeYId = 101;

}  // namespace

struct PipelineObjects {
  Handle<VkDescriptorSetLayout> set_layout;
  Handle<VkPipelineLayout> layout;
  Handle<VkPipeline> pipeline;
};

namespace {

std::shared_ptr<PipelineObjects> create_pipeline(VkDevice device, std::span<const std::uint32_t> spirv,
                                                 const std::vector<VkDescriptorType>& bindings,
                                                 std::uint32_t push_constant_bytes,
                                                 const std::vector<std::int32_t>& values) {
  auto objects = std::make_shared<PipelineObjects>();
  std::vector<VkDescriptorSetLayoutBinding> layout_bindings;
  for (std::uint32_t i = 0; i < bindings.size(); ++i)
    layout_bindings.push_back({i, bindings[i], 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.bindingCount = static_cast<std::uint32_t>(layout_bindings.size());
  set_info.pBindings = layout_bindings.data();
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VK_CHECK(vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout));
  objects->set_layout = {set_layout,
                         [device](VkDescriptorSetLayout l) { vkDestroyDescriptorSetLayout(device, l, nullptr); }};

  const VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_constant_bytes};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &set_layout;
  layout_info.pushConstantRangeCount = push_constant_bytes > 0 ? 1 : 0;
  layout_info.pPushConstantRanges = &range;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VK_CHECK(vkCreatePipelineLayout(device, &layout_info, nullptr, &layout));
  objects->layout = {layout, [device](VkPipelineLayout l) { vkDestroyPipelineLayout(device, l, nullptr); }};

  VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  module_info.codeSize = spirv.size_bytes();
  module_info.pCode = spirv.data();
  VkShaderModule module = VK_NULL_HANDLE;
  VK_CHECK(vkCreateShaderModule(device, &module_info, nullptr, &module));
  Handle<VkShaderModule> module_owner(module, [device](VkShaderModule m) { vkDestroyShaderModule(device, m, nullptr); });

  // values: user constants at ids 0.., then the workgroup size at kLocalSizeXId, kLocalSizeYId.
  std::vector<VkSpecializationMapEntry> entries;
  const auto user = static_cast<std::uint32_t>(values.size() - 2);
  for (std::uint32_t i = 0; i < user; ++i) entries.push_back({i, i * 4u, 4});
  entries.push_back({kLocalSizeXId, user * 4u, 4});
  entries.push_back({kLocalSizeYId, (user + 1) * 4u, 4});
  VkSpecializationInfo spec{static_cast<std::uint32_t>(entries.size()), entries.data(), values.size() * 4, values.data()};

  VkComputePipelineCreateInfo pipeline_info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  pipeline_info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  pipeline_info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  pipeline_info.stage.module = module;
  pipeline_info.stage.pName = "main";
  pipeline_info.stage.pSpecializationInfo = &spec;
  pipeline_info.layout = layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VK_CHECK(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline));
  objects->pipeline = {pipeline, [device](VkPipeline p) { vkDestroyPipeline(device, p, nullptr); }};
  return objects;
}

}  // namespace

ComputePipeline::ComputePipeline(Context& ctx, std::span<const std::uint32_t> spirv,
                                 std::vector<VkDescriptorType> bindings, std::uint32_t push_constant_bytes,
                                 std::vector<std::int32_t> specialization)
    : ctx_(ctx), push_constant_bytes_(push_constant_bytes) {
  const VkDevice device = ctx.device();
  std::vector<std::int32_t> values = specialization;
  values.push_back(static_cast<std::int32_t>(local_size_x_));
  values.push_back(static_cast<std::int32_t>(local_size_y_));
  std::string key = fmt::format("{}:{}:{}:", static_cast<const void*>(spirv.data()), spirv.size(), push_constant_bytes);
  for (VkDescriptorType type : bindings) key += fmt::format("b{}", static_cast<int>(type));
  for (std::int32_t v : values) key += fmt::format("s{}", v);
  auto& cached = ctx.pipeline_cache()[key];
  if (!cached) cached = create_pipeline(device, spirv, bindings, push_constant_bytes, values);
  shared_ = cached;
  const VkDescriptorSetLayout set_layout = shared_->set_layout;

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
  alloc.pSetLayouts = &set_layout;
  VK_CHECK(vkAllocateDescriptorSets(device, &alloc, &set_));
}

void ComputePipeline::write_descriptor(std::uint32_t binding, VkDescriptorType type,
                                       const VkDescriptorBufferInfo* buffer, const VkDescriptorImageInfo* image) {
  VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  write.dstSet = set_;
  write.dstBinding = binding;
  write.descriptorCount = 1;
  write.descriptorType = type;
  write.pBufferInfo = buffer;
  write.pImageInfo = image;
  vkUpdateDescriptorSets(ctx_.device(), 1, &write, 0, nullptr);
}

void ComputePipeline::bind(std::uint32_t binding, const Buffer& buffer) {
  const VkDescriptorBufferInfo info{buffer.get(), 0, VK_WHOLE_SIZE};
  write_descriptor(binding, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, &info, nullptr);
}

void ComputePipeline::bind(std::uint32_t binding, const StorageImage3D& image) {
  const VkDescriptorImageInfo info{VK_NULL_HANDLE, image.view(), VK_IMAGE_LAYOUT_GENERAL};
  write_descriptor(binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, nullptr, &info);
}

void ComputePipeline::dispatch(VkCommandBuffer cmd, const void* push_constants, std::uint32_t invocations_x,
                               std::uint32_t invocations_y) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, shared_->pipeline);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, shared_->layout, 0, 1, &set_, 0, nullptr);
  if (push_constant_bytes_ > 0)
    vkCmdPushConstants(cmd, shared_->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, push_constant_bytes_, push_constants);
  ++ctx_.commands_recorded;
  vkCmdDispatch(cmd, (invocations_x + local_size_x_ - 1) / local_size_x_,
                (invocations_y + local_size_y_ - 1) / local_size_y_, 1);
  // The next pass, or a vkCmdFillBuffer that resets a buffer for the next frame of a batch (which must
  // wait for this pass's reads too: the synchronization layer's write-after-read hazard).
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &barrier,
                       0, nullptr, 0, nullptr);
}

}  // namespace bokeh::vk
