#include "graphics_pipeline.hpp"

#include <fmt/format.h>

#include "vk_check.hpp"

namespace bokeh::vk {

namespace {

constexpr VkShaderStageFlags kStages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;

Handle<VkRenderPass> create_render_pass(VkDevice device, VkFormat format) {
  // The target rests in COLOR_ATTACHMENT_OPTIMAL before and after: no layout transition (and so no
  // implicit dependency) inside the pass; the copies around it carry the barriers.
  VkAttachmentDescription attachment{};
  attachment.format = format;
  attachment.samples = VK_SAMPLE_COUNT_1_BIT;
  attachment.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  attachment.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  attachment.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  attachment.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  attachment.initialLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  attachment.finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  const VkAttachmentReference color{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &color;
  VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  info.attachmentCount = 1;
  info.pAttachments = &attachment;
  info.subpassCount = 1;
  info.pSubpasses = &subpass;
  VkRenderPass pass = VK_NULL_HANDLE;
  VK_CHECK(vkCreateRenderPass(device, &info, nullptr, &pass));
  return {pass, [device](VkRenderPass p) { vkDestroyRenderPass(device, p, nullptr); }};
}

std::shared_ptr<PipelineObjects> create_pipeline(VkDevice device, VkFormat format,
                                                 std::span<const std::uint32_t> vertex_spirv,
                                                 std::span<const std::uint32_t> fragment_spirv,
                                                 const std::vector<VkDescriptorType>& bindings,
                                                 std::uint32_t push_constant_bytes, GraphicsPipeline::Blend blend) {
  auto objects = std::make_shared<PipelineObjects>();
  objects->render_pass = create_render_pass(device, format);
  create_layouts(device, bindings, kStages, push_constant_bytes, *objects);
  const Handle<VkShaderModule> vertex = create_shader_module(device, vertex_spirv);
  const Handle<VkShaderModule> fragment = create_shader_module(device, fragment_spirv);

  VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                               {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vertex;
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = fragment;
  stages[1].pName = "main";

  const VkPipelineVertexInputStateCreateInfo vertex_input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  viewport.viewportCount = 1;  // dynamic: the rectangle drawn changes (warm-up draws a corner)
  viewport.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.polygonMode = VK_POLYGON_MODE_FILL;
  raster.cullMode = VK_CULL_MODE_NONE;  // winding does not matter to off-screen sprites
  raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  raster.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;  // one sample at each pixel centre
  VkPipelineColorBlendAttachmentState attachment{};
  attachment.blendEnable = blend == GraphicsPipeline::Blend::additive ? VK_TRUE : VK_FALSE;
  attachment.srcColorBlendFactor = attachment.dstColorBlendFactor = VK_BLEND_FACTOR_ONE;
  attachment.srcAlphaBlendFactor = attachment.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
  attachment.colorBlendOp = attachment.alphaBlendOp = VK_BLEND_OP_ADD;
  attachment.colorWriteMask =
      VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo color_blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  color_blend.attachmentCount = 1;
  color_blend.pAttachments = &attachment;
  const VkDynamicState dynamic_states[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dynamic.dynamicStateCount = 2;
  dynamic.pDynamicStates = dynamic_states;

  VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  info.stageCount = 2;
  info.pStages = stages;
  info.pVertexInputState = &vertex_input;
  info.pInputAssemblyState = &assembly;
  info.pViewportState = &viewport;
  info.pRasterizationState = &raster;
  info.pMultisampleState = &multisample;
  info.pColorBlendState = &color_blend;
  info.pDynamicState = &dynamic;
  info.layout = objects->layout;
  info.renderPass = objects->render_pass;
  info.subpass = 0;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VK_CHECK(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline));
  objects->pipeline = {pipeline, [device](VkPipeline p) { vkDestroyPipeline(device, p, nullptr); }};
  return objects;
}

std::shared_ptr<PipelineObjects> cached_pipeline(Context& ctx, VkFormat format,
                                                 std::span<const std::uint32_t> vertex_spirv,
                                                 std::span<const std::uint32_t> fragment_spirv,
                                                 const std::vector<VkDescriptorType>& bindings,
                                                 std::uint32_t push_constant_bytes, GraphicsPipeline::Blend blend) {
  std::string key = fmt::format("graphics:{}:{}:{}:{}:{}:f{}:blend{}", static_cast<const void*>(vertex_spirv.data()),
                                vertex_spirv.size(), static_cast<const void*>(fragment_spirv.data()),
                                fragment_spirv.size(), push_constant_bytes, static_cast<int>(format),
                                static_cast<int>(blend));
  for (VkDescriptorType type : bindings) key += fmt::format("b{}", static_cast<int>(type));
  auto& cached = ctx.pipeline_cache()[key];
  if (!cached)
    cached = create_pipeline(ctx.device(), format, vertex_spirv, fragment_spirv, bindings, push_constant_bytes, blend);
  return cached;
}

VkImageMemoryBarrier image_barrier(const ColorTarget& target, VkImageLayout from, VkImageLayout to,
                                   VkAccessFlags src_access, VkAccessFlags dst_access) {
  VkImageMemoryBarrier barrier{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  barrier.srcAccessMask = src_access;
  barrier.dstAccessMask = dst_access;
  barrier.oldLayout = from;
  barrier.newLayout = to;
  barrier.srcQueueFamilyIndex = barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  barrier.image = target.image();
  barrier.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  return barrier;
}

VkBufferImageCopy region(std::uint32_t width, std::uint32_t height) {
  VkBufferImageCopy copy{};
  copy.bufferRowLength = width;
  copy.bufferImageHeight = height;
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {width, height, 1};
  return copy;
}

}  // namespace

GraphicsPipeline::GraphicsPipeline(Context& ctx, const ColorTarget& target, std::span<const std::uint32_t> vertex_spirv,
                                   std::span<const std::uint32_t> fragment_spirv,
                                   std::vector<VkDescriptorType> bindings, std::uint32_t push_constant_bytes,
                                   Blend blend)
    : ctx_(ctx),
      push_constant_bytes_(push_constant_bytes),
      shared_(cached_pipeline(ctx, target.format(), vertex_spirv, fragment_spirv, bindings, push_constant_bytes, blend)),
      set_(ctx, shared_->set_layout, bindings) {
  const VkImageView view = target.view();
  VkFramebufferCreateInfo info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
  info.renderPass = shared_->render_pass;
  info.attachmentCount = 1;
  info.pAttachments = &view;
  info.width = target.width();
  info.height = target.height();
  info.layers = 1;
  VkFramebuffer framebuffer = VK_NULL_HANDLE;
  VK_CHECK(vkCreateFramebuffer(ctx.device(), &info, nullptr, &framebuffer));
  framebuffer_ = {framebuffer, [d = ctx.device()](VkFramebuffer f) { vkDestroyFramebuffer(d, f, nullptr); }};
}

void GraphicsPipeline::bind(std::uint32_t binding, const Buffer& buffer) { set_.bind(binding, buffer); }

void GraphicsPipeline::draw_indirect(VkCommandBuffer cmd, const void* push_constants, std::uint32_t width,
                                     std::uint32_t height, const Buffer& args, VkDeviceSize offset) const {
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT |
                           VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                       0, 1, &barrier, 0, nullptr, 0, nullptr);

  VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  begin.renderPass = shared_->render_pass;
  begin.framebuffer = framebuffer_;
  begin.renderArea = {{0, 0}, {width, height}};
  vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, shared_->pipeline);
  const VkDescriptorSet set = set_.get();
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, shared_->layout, 0, 1, &set, 0, nullptr);
  if (push_constant_bytes_ > 0) vkCmdPushConstants(cmd, shared_->layout, kStages, 0, push_constant_bytes_, push_constants);
  const VkViewport viewport{0.0f, 0.0f, static_cast<float>(width), static_cast<float>(height), 0.0f, 1.0f};
  const VkRect2D scissor{{0, 0}, {width, height}};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
  ++ctx_.commands_recorded;
  vkCmdDrawIndirect(cmd, args.get(), offset, 1, sizeof(VkDrawIndirectCommand));
  vkCmdEndRenderPass(cmd);
}

void copy_to_target(VkCommandBuffer cmd, const Buffer& src, const ColorTarget& target, std::uint32_t width,
                    std::uint32_t height) {
  VkMemoryBarrier written{VK_STRUCTURE_TYPE_MEMORY_BARRIER};  // the pass that filled `src`
  written.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  written.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  const VkImageMemoryBarrier to_transfer =
      image_barrier(target, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                    VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  vkCmdPipelineBarrier(cmd,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                           VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &written, 0, nullptr, 1, &to_transfer);
  const VkBufferImageCopy copy = region(width, height);
  vkCmdCopyBufferToImage(cmd, src.get(), target.image(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
  const VkImageMemoryBarrier to_draw = image_barrier(
      target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
      VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0,
                       nullptr, 0, nullptr, 1, &to_draw);
}

void copy_from_target(VkCommandBuffer cmd, const ColorTarget& target, const Buffer& dst, std::uint32_t width,
                      std::uint32_t height) {
  // Also waits for earlier passes and copies still reading `dst` (write after read).
  const VkImageMemoryBarrier to_transfer =
      image_barrier(target, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                    VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT);
  vkCmdPipelineBarrier(cmd,
                       VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                           VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &to_transfer);
  const VkBufferImageCopy copy = region(width, height);
  vkCmdCopyImageToBuffer(cmd, target.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, dst.get(), 1, &copy);
  VkMemoryBarrier written{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  written.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  written.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                          VK_ACCESS_TRANSFER_WRITE_BIT;
  const VkImageMemoryBarrier to_rest = image_barrier(
      target, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, 0,
      VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT |
                           VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                       0, 1, &written, 0, nullptr, 1, &to_rest);
}

}  // namespace bokeh::vk
