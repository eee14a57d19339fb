#pragma once
// VK_CHECK: every Vulkan call that returns a VkResult goes through it; failure throws VulkanError
// naming the call and the result, so errors reach the user as a message and a non-zero exit.
#include <stdexcept>
#include <string>

#include <vulkan/vulkan.h>

namespace bokeh::vk {

std::string result_name(VkResult result);

class VulkanError : public std::runtime_error {
 public:
  VulkanError(const char* call, VkResult result)
      : std::runtime_error(std::string(call) + " failed: " + result_name(result)), result_(result) {}
  VkResult result() const { return result_; }

 private:
  VkResult result_;
};

}  // namespace bokeh::vk

#define VK_CHECK(call)                                                   \
  do {                                                                   \
    const VkResult vk_check_result_ = (call);                            \
    if (vk_check_result_ != VK_SUCCESS)                                  \
      throw ::bokeh::vk::VulkanError(#call, vk_check_result_);           \
  } while (false)
