#pragma once
// A compute shader with its descriptor set (storage buffers and storage images, in binding
// order), push constants and integer specialization constants. The compiled pipeline is shared
// through the context's cache; each ComputePipeline owns only its descriptor set.
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

class ComputePipeline {
 public:
  ComputePipeline(Context& ctx, std::span<const std::uint32_t> spirv, std::vector<VkDescriptorType> bindings,
                  std::uint32_t push_constant_bytes, std::vector<std::int32_t> specialization = {});

  void bind(std::uint32_t binding, const Buffer& buffer);
  void bind(std::uint32_t binding, const StorageImage3D& image);

  // Binds, pushes constants, dispatches enough workgroups to cover `invocations`, and ends with a
  // barrier so the next pass sees this pass's writes.
  void dispatch(VkCommandBuffer cmd, const void* push_constants, std::uint32_t invocations_x,
                std::uint32_t invocations_y) const;

 private:
  Context& ctx_;
  std::uint32_t push_constant_bytes_;
  std::uint32_t local_size_x_ = 8, local_size_y_ = 8;
  std::shared_ptr<PipelineObjects> shared_;
  DescriptorSet set_;
};

}  // namespace bokeh::vk
