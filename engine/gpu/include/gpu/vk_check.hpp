#pragma once
#include <stdexcept>
#include <string>

#include <vulkan/vulkan.h>

namespace engine::gpu {

const char* vk_result_name(VkResult result);

// A Vulkan call failed that the engine cannot continue without.
class VulkanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] void throw_vk_error(VkResult result, const char* call, const char* file, int line);

}  // namespace engine::gpu

#define VK_CHECK(call)                                                                 \
  do {                                                                                 \
    VkResult vk_check_result_ = (call);                                                \
    if (vk_check_result_ < 0) ::engine::gpu::throw_vk_error(vk_check_result_, #call, __FILE__, __LINE__); \
  } while (0)
