#pragma once
// The one Vulkan context: instance, the chosen physical device, a compute queue, and a command
// buffer for synchronous submissions. Everything GPU-side borrows it.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "handle.hpp"

namespace bokeh::vk {

struct DeviceInfo {
  int index = -1;
  std::string name;
  std::string type;  // discrete, integrated, virtual, cpu, other
  std::string api_version;
  std::string driver_name;  // e.g. llvmpipe
  std::string driver_info;  // e.g. "Mesa 22.3.6 (LLVM 15.0.6)"
  std::uint32_t vendor_id = 0, device_id = 0;
  double timestamp_period_ns = 0;
  std::uint32_t timestamp_valid_bits = 0;
  std::uint64_t max_storage_buffer_range_bytes = 0;
  std::uint64_t max_uniform_buffer_range_bytes = 0;
  std::uint64_t max_texel_buffer_elements = 0;
  std::uint32_t max_image_dimension_3d = 0;
  std::uint64_t device_local_heap_bytes = 0;
  bool pipeline_statistics = false;  // pipelineStatisticsQuery (enabled when present)
  VkSubgroupFeatureFlags subgroup_operations = 0;  // in compute shaders (0: none there)
  bool has_subgroup_operations(VkSubgroupFeatureFlags wanted) const { return (subgroup_operations & wanted) == wanted; }
  bool is_software() const { return type == "cpu"; }
};

// All devices the loader reports, in the order `--device INDEX` uses.
std::vector<DeviceInfo> list_devices();

// What a method needs of a device beyond core Vulkan 1.1 compute (Method::device).
struct DeviceRequirements {
  VkSubgroupFeatureFlags subgroup_operations = 0;     // VK_SUBGROUP_FEATURE_*_BIT it uses in compute shaders
  std::vector<VkFormat> storage_image_3d_formats;     // formats it stores into 3D storage images
  bool graphics_queue = false;                        // it draws (graphics pipeline on the same queue)
  std::vector<VkFormat> blend_attachment_formats;     // formats it draws into with blending
  // Not a method's: `check` asks for it so an out-of-bounds access under the validation layer is
  // reported rather than corrupting memory or crashing (reads give 0 or in-bounds values, writes drop).
  bool robust_buffer_access = false;
  void add(const DeviceRequirements& other);          // the union of both
};

struct PipelineObjects;  // pipeline_objects.hpp: layouts and pipeline shared by equal pipelines
class MemoryBlocks;      // memory.cpp: the blocks small allocations share

// A submission that ran past the watchdog: the device still runs it (handle.hpp, device_abandoned).
struct RunawaySubmission : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Context {
 public:
  // selector: "" picks the best device (discrete > integrated > virtual > cpu) among those meeting
  // `wanted`, or the best of all when none does; a number picks that index; anything else picks the
  // first device whose name contains it. Throws if nothing matches.
  explicit Context(const std::string& selector = "", const DeviceRequirements& wanted = {});
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const { return info_; }
  VkDevice device() const { return device_; }
  VkPhysicalDevice physical_device() const { return physical_; }

  // Records with `record`, submits, and waits: lavapipe runs dispatches synchronously anyway, and
  // a benchmark wants each frame finished before it reads the timestamps.
  // With watchdog_floor_s > 0 the wait is bounded: a submission running past watchdog_floor_s +
  // 20 x watchdog_expected_s throws RunawaySubmission, and the device is abandoned (handle.hpp).
  void submit_and_wait(const std::function<void(VkCommandBuffer)>& record);
  double watchdog_floor_s = 0;     // 0: wait as long as it takes
  double watchdog_expected_s = 0;  // what the caller expects the next submission to take

  // What of `wanted` this device lacks, in words ("" when it has everything).
  std::string unmet(const DeviceRequirements& wanted) const;

  // Equal pipelines (same SPIR-V, bindings, constants) share one compiled pipeline: a sweep that
  // re-creates a method's passes neither recompiles nor re-JITs them (lavapipe compiles on first use).
  std::map<std::string, std::shared_ptr<PipelineObjects>>& pipeline_cache() { return pipeline_cache_; }

  // Dispatches and draws recorded so far (the recording wrappers count them; TimestampQueries
  // attributes them to passes).
  std::uint64_t commands_recorded = 0;

  std::uint32_t find_memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags wanted,
                                 VkMemoryPropertyFlags fallback) const;

  // Where small buffers and images are sub-allocated (memory.hpp, Allocation).
  MemoryBlocks& memory_blocks();

 private:
  Handle<VkInstance> instance_;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  Handle<VkDevice> device_;
  std::map<std::string, std::shared_ptr<PipelineObjects>> pipeline_cache_;  // destroyed before the device
  std::unique_ptr<MemoryBlocks> memory_blocks_;                              // likewise
  VkQueue queue_ = VK_NULL_HANDLE;
  std::uint32_t queue_family_ = 0;
  Handle<VkCommandPool> command_pool_;
  VkCommandBuffer command_buffer_ = VK_NULL_HANDLE;
  Handle<VkFence> fence_;
  DeviceInfo info_;
  VkPhysicalDeviceMemoryProperties memory_{};
};

}  // namespace bokeh::vk
