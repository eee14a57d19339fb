#include "vk_check.hpp"

// Vulkan-Hpp already knows every VkResult's name; only this file pays for including it.
#include <vulkan/vulkan.hpp>

namespace bokeh::vk {

std::string result_name(VkResult result) { return ::vk::to_string(static_cast<::vk::Result>(result)); }

}  // namespace bokeh::vk
