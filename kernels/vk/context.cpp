#include "context.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "memory.hpp"  // MemoryBlocks, owned here
#include "vk_check.hpp"

namespace bokeh::vk {

namespace {

Handle<VkInstance> create_instance() {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "bokehbench";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult result = vkCreateInstance(&info, nullptr, &instance);
  if (result == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw std::runtime_error(
        "no Vulkan driver found: install mesa-vulkan-drivers (lavapipe) or your GPU's Vulkan driver");
  VK_CHECK(result);
  return {instance, [](VkInstance i) { vkDestroyInstance(i, nullptr); }};
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance instance) {
  std::uint32_t count = 0;
  VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, nullptr));
  std::vector<VkPhysicalDevice> devices(count);
  VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, devices.data()));
  return devices;
}

std::string type_name(VkPhysicalDeviceType type) {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

int preference(const DeviceInfo& d) {
  const char* order[] = {"discrete", "integrated", "virtual", "other", "cpu"};
  return static_cast<int>(std::find(std::begin(order), std::end(order), d.type) - std::begin(order));
}

// The subgroup operations compute shaders have on `device` (0 where compute has none).
VkSubgroupFeatureFlags compute_subgroup_operations(VkPhysicalDevice device) {
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &subgroup};
  vkGetPhysicalDeviceProperties2(device, &props);
  return (subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ? subgroup.supportedOperations : 0;
}

DeviceInfo describe(VkPhysicalDevice device, int index) {
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props.pNext = &driver;
  vkGetPhysicalDeviceProperties2(device, &props);
  const auto& p = props.properties;
  DeviceInfo info;
  info.index = index;
  info.name = p.deviceName;
  info.type = type_name(p.deviceType);
  info.api_version = fmt::format("{}.{}.{}", VK_API_VERSION_MAJOR(p.apiVersion), VK_API_VERSION_MINOR(p.apiVersion),
                                 VK_API_VERSION_PATCH(p.apiVersion));
  info.driver_name = driver.driverName;
  info.driver_info = driver.driverInfo;
  info.vendor_id = p.vendorID;
  info.device_id = p.deviceID;
  info.timestamp_period_ns = p.limits.timestampPeriod;
  info.max_storage_buffer_range_bytes = p.limits.maxStorageBufferRange;
  info.max_uniform_buffer_range_bytes = p.limits.maxUniformBufferRange;
  info.max_texel_buffer_elements = p.limits.maxTexelBufferElements;
  info.max_image_dimension_3d = p.limits.maxImageDimension3D;
  info.subgroup_operations = compute_subgroup_operations(device);

  std::uint32_t family_count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(device, &family_count, nullptr);
  std::vector<VkQueueFamilyProperties> families(family_count);
  vkGetPhysicalDeviceQueueFamilyProperties(device, &family_count, families.data());
  for (const auto& f : families)
    if (f.queueFlags & VK_QUEUE_COMPUTE_BIT) {
      info.timestamp_valid_bits = f.timestampValidBits;
      break;
    }
  VkPhysicalDeviceMemoryProperties memory{};
  vkGetPhysicalDeviceMemoryProperties(device, &memory);
  for (std::uint32_t h = 0; h < memory.memoryHeapCount; ++h)
    if (memory.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      info.device_local_heap_bytes = std::max<std::uint64_t>(info.device_local_heap_bytes, memory.memoryHeaps[h].size);
  return info;
}

// "subgroup ballot, shuffle": the operation classes among `flags` (by number where Vulkan 1.1 has no name).
std::string subgroup_operations_text(VkSubgroupFeatureFlags flags) {
  static const std::pair<VkSubgroupFeatureFlagBits, const char*> names[] = {
      {VK_SUBGROUP_FEATURE_BASIC_BIT, "basic"},
      {VK_SUBGROUP_FEATURE_VOTE_BIT, "vote"},
      {VK_SUBGROUP_FEATURE_ARITHMETIC_BIT, "arithmetic"},
      {VK_SUBGROUP_FEATURE_BALLOT_BIT, "ballot"},
      {VK_SUBGROUP_FEATURE_SHUFFLE_BIT, "shuffle"},
      {VK_SUBGROUP_FEATURE_SHUFFLE_RELATIVE_BIT, "relative shuffle"},
      {VK_SUBGROUP_FEATURE_CLUSTERED_BIT, "clustered"},
      {VK_SUBGROUP_FEATURE_QUAD_BIT, "quad"}};
  std::string text;
  auto add = [&text](const std::string& name) { text += (text.empty() ? "subgroup " : ", ") + name; };
  for (const auto& [bit, name] : names)
    if (flags & bit) {
      add(name);
      flags &= ~static_cast<VkSubgroupFeatureFlags>(bit);
    }
  if (flags) add(fmt::format("operations 0x{:x}", flags));
  return text;
}

std::string unmet_by(VkPhysicalDevice device, const DeviceRequirements& wanted) {
  std::vector<std::string> missing;
  const VkSubgroupFeatureFlags subgroup_missing = wanted.subgroup_operations & ~compute_subgroup_operations(device);
  if (subgroup_missing) missing.push_back(subgroup_operations_text(subgroup_missing) + " in compute shaders");
  for (VkFormat format : wanted.storage_image_3d_formats) {
    VkImageFormatProperties props{};
    if (vkGetPhysicalDeviceImageFormatProperties(device, format, VK_IMAGE_TYPE_3D, VK_IMAGE_TILING_OPTIMAL,
                                                 VK_IMAGE_USAGE_STORAGE_BIT, 0, &props) != VK_SUCCESS)
      missing.push_back(fmt::format("3D storage images of format {}", static_cast<int>(format)));
  }
  for (VkFormat format : wanted.blend_attachment_formats) {
    VkFormatProperties props{};
    vkGetPhysicalDeviceFormatProperties(device, format, &props);
    if (!(props.optimalTilingFeatures & VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT))
      missing.push_back(fmt::format("blending into colour attachments of format {}", static_cast<int>(format)));
  }
  if (wanted.robust_buffer_access) {
    VkPhysicalDeviceFeatures features{};
    vkGetPhysicalDeviceFeatures(device, &features);
    if (!features.robustBufferAccess) missing.push_back("robust buffer access");
  }
  if (wanted.graphics_queue) {
    std::uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(device, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(device, &count, families.data());
    if (std::none_of(families.begin(), families.end(), [](const auto& f) {
          return (f.queueFlags & VK_QUEUE_GRAPHICS_BIT) && (f.queueFlags & VK_QUEUE_COMPUTE_BIT) && f.timestampValidBits;
        }))
      missing.push_back("a queue with graphics, compute and timestamps");
  }
  std::string text;
  for (const auto& m : missing) text += (text.empty() ? "" : ", ") + m;
  return text;
}

}  // namespace

void DeviceRequirements::add(const DeviceRequirements& other) {
  subgroup_operations |= other.subgroup_operations;
  graphics_queue |= other.graphics_queue;
  robust_buffer_access |= other.robust_buffer_access;
  for (VkFormat f : other.storage_image_3d_formats)
    if (std::find(storage_image_3d_formats.begin(), storage_image_3d_formats.end(), f) == storage_image_3d_formats.end())
      storage_image_3d_formats.push_back(f);
  for (VkFormat f : other.blend_attachment_formats)
    if (std::find(blend_attachment_formats.begin(), blend_attachment_formats.end(), f) == blend_attachment_formats.end())
      blend_attachment_formats.push_back(f);
}

std::vector<DeviceInfo> list_devices() {
  Handle<VkInstance> instance = create_instance();
  std::vector<DeviceInfo> infos;
  const auto devices = physical_devices(instance);
  for (std::size_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], static_cast<int>(i)));
  return infos;
}

Context::Context(const std::string& selector, const DeviceRequirements& wanted) : instance_(create_instance()) {
  const auto devices = physical_devices(instance_);
  if (devices.empty()) throw std::runtime_error("the Vulkan loader reports no devices (is mesa-vulkan-drivers installed?)");
  std::vector<DeviceInfo> infos;
  for (std::size_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], static_cast<int>(i)));

  const DeviceInfo* chosen = nullptr;
  if (selector.empty()) {
    // By type (a real GPU over lavapipe even if it misses a feature: those methods are skipped with
    // the reason); among devices of one type, one that meets `wanted`.
    auto rank = [&](const DeviceInfo& d) { return 2 * preference(d) + (unmet_by(devices[d.index], wanted).empty() ? 0 : 1); };
    chosen = &*std::min_element(infos.begin(), infos.end(), [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
  } else if (std::all_of(selector.begin(), selector.end(), ::isdigit)) {
    // Compared as text first: an index too long for an int names no device either.
    if (selector.size() > 9 || std::stoi(selector) >= static_cast<int>(infos.size()))
      throw std::invalid_argument(fmt::format("--device {}: only {} device(s), see `bokehbench devices`", selector, infos.size()));
    chosen = &infos[std::stoi(selector)];
  } else {
    for (const auto& d : infos)
      if (d.name.find(selector) != std::string::npos) {
        chosen = &d;
        break;
      }
    if (!chosen) throw std::invalid_argument(fmt::format("--device '{}' matches no device, see `bokehbench devices`", selector));
  }
  info_ = *chosen;
  physical_ = devices[info_.index];
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

  std::uint32_t family_count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &family_count, nullptr);
  std::vector<VkQueueFamilyProperties> families(family_count);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_, &family_count, families.data());
  // A queue that also draws where there is one (a method may need graphics), else compute alone.
  auto family = std::find_if(families.begin(), families.end(), [](const auto& f) {
    return (f.queueFlags & VK_QUEUE_GRAPHICS_BIT) && (f.queueFlags & VK_QUEUE_COMPUTE_BIT) && f.timestampValidBits > 0;
  });
  if (family == families.end())
    family = std::find_if(families.begin(), families.end(),
                          [](const auto& f) { return (f.queueFlags & VK_QUEUE_COMPUTE_BIT) && f.timestampValidBits > 0; });
  if (family == families.end())
    throw std::runtime_error(fmt::format("device '{}' has no compute queue with timestamps", info_.name));
  queue_family_ = static_cast<std::uint32_t>(family - families.begin());

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue_info.queueFamilyIndex = queue_family_;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;
  VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  device_info.queueCreateInfoCount = 1;
  device_info.pQueueCreateInfos = &queue_info;
  VkPhysicalDeviceFeatures supported{}, features{};
  vkGetPhysicalDeviceFeatures(physical_, &supported);
  features.pipelineStatisticsQuery = supported.pipelineStatisticsQuery;
  info_.pipeline_statistics = supported.pipelineStatisticsQuery == VK_TRUE;
  features.robustBufferAccess = wanted.robust_buffer_access ? supported.robustBufferAccess : VK_FALSE;
  device_info.pEnabledFeatures = &features;
  VkDevice device = VK_NULL_HANDLE;
  VK_CHECK(vkCreateDevice(physical_, &device_info, nullptr, &device));
  device_ = Handle<VkDevice>(device, [](VkDevice d) { vkDestroyDevice(d, nullptr); });
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.queueFamilyIndex = queue_family_;
  VkCommandPool pool = VK_NULL_HANDLE;
  VK_CHECK(vkCreateCommandPool(device_, &pool_info, nullptr, &pool));
  command_pool_ = Handle<VkCommandPool>(pool, [d = device](VkCommandPool p) { vkDestroyCommandPool(d, p, nullptr); });

  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = command_pool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VK_CHECK(vkAllocateCommandBuffers(device_, &alloc, &command_buffer_));

  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence = VK_NULL_HANDLE;
  VK_CHECK(vkCreateFence(device_, &fence_info, nullptr, &fence));
  fence_ = Handle<VkFence>(fence, [d = device](VkFence f) { vkDestroyFence(d, f, nullptr); });
}

Context::~Context() {
  if (device_.get() != VK_NULL_HANDLE && !device_abandoned()) vkDeviceWaitIdle(device_);
}

void Context::submit_and_wait(const std::function<void(VkCommandBuffer)>& record) {
  if (device_abandoned())
    throw std::runtime_error("the device is still running an earlier submission that ran past the watchdog; nothing "
                             "more can run on it in this process");
  VK_CHECK(vkResetCommandPool(device_, command_pool_, 0));  // its one buffer: cheaper than a per-buffer reset
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_CHECK(vkBeginCommandBuffer(command_buffer_, &begin));
  record(command_buffer_);
  VK_CHECK(vkEndCommandBuffer(command_buffer_));
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &command_buffer_;
  VkFence fence = fence_;
  VK_CHECK(vkResetFences(device_, 1, &fence));
  VK_CHECK(vkQueueSubmit(queue_, 1, &submit, fence));
  if (!(watchdog_floor_s > 0)) {
    VK_CHECK(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX));
    return;
  }
  const double limit_s = watchdog_floor_s + 20 * std::max(0.0, watchdog_expected_s);
  const VkResult waited = vkWaitForFences(device_, 1, &fence, VK_TRUE, static_cast<std::uint64_t>(limit_s * 1e9));
  if (waited == VK_TIMEOUT) {
    device_abandoned() = true;
    throw RunawaySubmission(fmt::format("ran past the watchdog of {:.3g} s ({:g} s, plus 20x the {:.3g} s expected)",
                                        limit_s, watchdog_floor_s, watchdog_expected_s));
  }
  VK_CHECK(waited);
}

std::string Context::unmet(const DeviceRequirements& wanted) const { return unmet_by(physical_, wanted); }

std::uint32_t Context::find_memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags wanted,
                                        VkMemoryPropertyFlags fallback) const {
  for (VkMemoryPropertyFlags flags : {wanted, fallback})
    for (std::uint32_t i = 0; i < memory_.memoryTypeCount; ++i)
      if ((type_bits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & flags) == flags) return i;
  throw std::runtime_error("no suitable Vulkan memory type");
}

}  // namespace bokeh::vk
