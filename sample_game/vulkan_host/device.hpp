#pragma once
// The host's own Vulkan objects: instance, device with what the shadow module asks for, and the few
// buffer and image helpers the program needs. Plain Vulkan; no engine header.
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "shadows/shadows.hpp"

namespace vulkan_host {

struct DeviceOptions {
  std::string device;            // "gpu", "lavapipe" or empty: a GPU if there is one, else lavapipe
  bool validation = false;       // the Khronos layer, every message counted (and printed as "[vulkan] ...")
  bool sync_validation = false;  // with the layer's synchronization checks
  // Extensions or feature bits the module asks for that this host leaves out (tests of its errors).
  std::vector<std::string> leave_out;
};

class Device {
 public:
  explicit Device(const DeviceOptions& options);  // throws std::runtime_error, one line
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // What shadows::Context::create needs, for this device.
  shadows::ContextDesc context_desc(uint32_t frames_in_flight, const shadows::Settings& settings) const;
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags flags) const;
  uint32_t validation_messages() const { return messages_; }

  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t family = 0;
  VkQueue queue = VK_NULL_HANDLE;
  std::string name;
  std::vector<const char*> instance_extensions;  // the array vkCreateInstance took (static names)
  std::unique_ptr<shadows::DeviceSetup> setup;  // the module's features and extensions, as created

 private:
  void create(const DeviceOptions& options);
  void release();  // what create() made, newest first (also when it threw part-way)
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  std::atomic<uint32_t> messages_{0};
  static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                   VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT*, void*);
};

// Host-visible, mapped: simple, and fast enough for a few meshes and read-backs.
struct Buffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  VkDeviceSize size = 0;
  VkBufferUsageFlags usage = 0;
  shadows::BufferInput input(VkDeviceSize offset = 0) const { return {buffer, offset, size - offset, usage}; }
};
Buffer make_buffer(const Device& d, VkDeviceSize size, VkBufferUsageFlags usage);
void destroy(const Device& d, Buffer& b);

// One 2D image with one mip and a view of its colour or depth aspect.
struct Image {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{};
  VkImageUsageFlags usage = 0;
  VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT;  // of the view
  shadows::ImageInput input(VkImageLayout layout) const { return {image, view, format, extent, usage, layout}; }
};
Image make_image(const Device& d, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage);
void destroy(const Device& d, Image& i);

// One image layout change (or none) and the memory dependency that comes with it.
void image_barrier(VkCommandBuffer cmd, const Image& image, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                   VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access, VkImageLayout from, VkImageLayout to);

void check(VkResult r, const char* what);  // throws std::runtime_error naming `what` unless VK_SUCCESS

}  // namespace vulkan_host
