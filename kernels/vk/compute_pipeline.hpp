#pragma once
// A compute shader with its descriptor set (storage and uniform buffers, uniform texel buffers and
// storage images, in binding order), push constants and integer specialization constants. The
// compiled pipeline is shared through the context's cache; each ComputePipeline owns only its
// descriptor set.
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

// The workgroup's size (local_size_x_id / local_size_y_id). 8 x 8 unless a shader needs its workgroup
// to be one unit of work (FLAG's scan: a row segment per workgroup, so its loads are uniform).
struct LocalSize {
  std::uint32_t x = 8, y = 8;
};

class ComputePipeline {
 public:
  ComputePipeline(Context& ctx, std::span<const std::uint32_t> spirv, std::vector<VkDescriptorType> bindings,
                  std::uint32_t push_constant_bytes, std::vector<std::int32_t> specialization = {},
                  LocalSize local_size = {});

  void bind(std::uint32_t binding, const Buffer& buffer);  // a storage or uniform buffer, as declared
  void bind(std::uint32_t binding, const StorageImage3D& image);
  void bind(std::uint32_t binding, const TexelView& view);  // a uniform texel buffer

  // Binds, pushes constants, dispatches enough workgroups to cover `invocations`, and ends with a
  // barrier so the next pass sees this pass's writes (as data or as indirect dispatch sizes).
  void dispatch(VkCommandBuffer cmd, const void* push_constants, std::uint32_t invocations_x,
                std::uint32_t invocations_y) const;
  // As dispatch, with the workgroup counts the VkDispatchIndirectCommand at `offset` in `args` holds
  // (written by an earlier pass; `args` made with VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT).
  void dispatch_indirect(VkCommandBuffer cmd, const void* push_constants, const Buffer& args,
                         VkDeviceSize offset) const;
  // The workgroups dispatch() launches to cover `invocations` (z = 1).
  VkDispatchIndirectCommand groups(std::uint32_t invocations_x, std::uint32_t invocations_y) const;

 private:
  void bind_and_push(VkCommandBuffer cmd, const void* push_constants) const;
  void barrier_after(VkCommandBuffer cmd) const;

  Context& ctx_;
  std::uint32_t push_constant_bytes_;
  LocalSize local_size_;
  std::shared_ptr<PipelineObjects> shared_;
  DescriptorSet set_;
};

}  // namespace bokeh::vk
