#include "compute_pipeline.hpp"

#include <fmt/format.h>

#include "vk_check.hpp"

namespace bokeh::vk {

namespace {

// Every shader declares local_size_x_id = 100 and local_size_y_id = 101 so the host knows them.
constexpr std::uint32_t kLocalSizeXId = 100, kLocalSizeYId = 101;

std::shared_ptr<PipelineObjects> create_pipeline(VkDevice device, std::span<const std::uint32_t> spirv,
                                                 const std::vector<VkDescriptorType>& bindings,
                                                 std::uint32_t push_constant_bytes,
                                                 const std::vector<std::int32_t>& values) {
  auto objects = std::make_shared<PipelineObjects>();
  create_layouts(device, bindings, VK_SHADER_STAGE_COMPUTE_BIT, push_constant_bytes, *objects);
  const Handle<VkShaderModule> module = create_shader_module(device, spirv);

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
  pipeline_info.layout = objects->layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VK_CHECK(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline));
  objects->pipeline = {pipeline, [device](VkPipeline p) { vkDestroyPipeline(device, p, nullptr); }};
  return objects;
}

// Equal pipelines (same SPIR-V, bindings, constants) share one compiled pipeline.
std::shared_ptr<PipelineObjects> cached_pipeline(Context& ctx, std::span<const std::uint32_t> spirv,
                                                 const std::vector<VkDescriptorType>& bindings,
                                                 std::uint32_t push_constant_bytes,
                                                 const std::vector<std::int32_t>& values) {
  std::string key = fmt::format("{}:{}:{}:", static_cast<const void*>(spirv.data()), spirv.size(), push_constant_bytes);
  for (VkDescriptorType type : bindings) key += fmt::format("b{}", static_cast<int>(type));
  for (std::int32_t v : values) key += fmt::format("s{}", v);
  auto& cached = ctx.pipeline_cache()[key];
  if (!cached) cached = create_pipeline(ctx.device(), spirv, bindings, push_constant_bytes, values);
  return cached;
}

std::vector<std::int32_t> with_local_size(std::vector<std::int32_t> values, std::uint32_t x, std::uint32_t y) {
  values.push_back(static_cast<std::int32_t>(x));
  values.push_back(static_cast<std::int32_t>(y));
  return values;
}

}  // namespace

ComputePipeline::ComputePipeline(Context& ctx, std::span<const std::uint32_t> spirv,
                                 std::vector<VkDescriptorType> bindings, std::uint32_t push_constant_bytes,
                                 std::vector<std::int32_t> specialization, LocalSize local_size)
    : ctx_(ctx),
      push_constant_bytes_(push_constant_bytes),
      local_size_(local_size),
      shared_(cached_pipeline(ctx, spirv, bindings, push_constant_bytes,
                              with_local_size(std::move(specialization), local_size.x, local_size.y))),
      set_(ctx, shared_->set_layout, bindings) {}

void ComputePipeline::bind(std::uint32_t binding, const Buffer& buffer) { set_.bind(binding, buffer); }

void ComputePipeline::bind(std::uint32_t binding, const StorageImage3D& image) { set_.bind(binding, image); }

void ComputePipeline::bind(std::uint32_t binding, const TexelView& view) { set_.bind(binding, view); }

void ComputePipeline::bind_and_push(VkCommandBuffer cmd, const void* push_constants) const {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, shared_->pipeline);
  const VkDescriptorSet set = set_.get();
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, shared_->layout, 0, 1, &set, 0, nullptr);
  if (push_constant_bytes_ > 0)
    vkCmdPushConstants(cmd, shared_->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, push_constant_bytes_, push_constants);
}

// The next pass may read this pass's writes as data or as indirect dispatch sizes; a
// vkCmdFillBuffer that resets a buffer for the next frame of a batch must wait for this pass's reads
// too (the synchronization layer's write-after-read hazard).
void ComputePipeline::barrier_after(VkCommandBuffer cmd) const {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                          VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT |
                           VK_PIPELINE_STAGE_TRANSFER_BIT,
                       0, 1, &barrier, 0, nullptr, 0, nullptr);
}

VkDispatchIndirectCommand ComputePipeline::groups(std::uint32_t invocations_x, std::uint32_t invocations_y) const {
  return {(invocations_x + local_size_.x - 1) / local_size_.x, (invocations_y + local_size_.y - 1) / local_size_.y, 1};
}

void ComputePipeline::dispatch(VkCommandBuffer cmd, const void* push_constants, std::uint32_t invocations_x,
                               std::uint32_t invocations_y) const {
  bind_and_push(cmd, push_constants);
  ++ctx_.commands_recorded;
  const VkDispatchIndirectCommand g = groups(invocations_x, invocations_y);
  vkCmdDispatch(cmd, g.x, g.y, g.z);
  barrier_after(cmd);
}

void ComputePipeline::dispatch_indirect(VkCommandBuffer cmd, const void* push_constants, const Buffer& args,
                                        VkDeviceSize offset) const {
  bind_and_push(cmd, push_constants);
  ++ctx_.commands_recorded;
  vkCmdDispatchIndirect(cmd, args.get(), offset);
  barrier_after(cmd);
}

}  // namespace bokeh::vk
