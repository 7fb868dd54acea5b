#include "device.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace vulkan_host {

void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS) throw std::runtime_error(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
}

VKAPI_ATTR VkBool32 VKAPI_CALL Device::on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                  VkDebugUtilsMessageTypeFlagsEXT,
                                                  const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  static_cast<Device*>(user)->messages_++;
  std::fprintf(stderr, "[vulkan] %s\n", data->pMessage);
  return VK_FALSE;
}

Device::Device(const DeviceOptions& options) {
  // A constructor that throws runs no destructor: what it made so far goes here.
  try {
    create(options);
  } catch (...) {
    release();
    throw;
  }
}

void Device::create(const DeviceOptions& options) {
  // Instance: Vulkan 1.3, with the validation layer (and its synchronization checks) when asked here or
  // by ENGINE_VALIDATION=1 / ENGINE_SYNC_VALIDATION=1 (the latter implies the layer).
  auto env = [](const char* name) { return std::getenv(name) && std::strcmp(std::getenv(name), "0") != 0; };
  const bool sync_validation = options.sync_validation || env("ENGINE_SYNC_VALIDATION");
  const bool validation = options.validation || sync_validation || env("ENGINE_VALIDATION");
  const char* layer = "VK_LAYER_KHRONOS_validation";
  std::vector<const char*> extensions;
  if (validation) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (sync_validation) extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
  VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messenger.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  messenger.pfnUserCallback = on_message;
  messenger.pUserData = this;
  const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT, &messenger, 1, &sync};
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "vulkan_host";
  app.apiVersion = VK_API_VERSION_1_3;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  if (validation) {
    info.enabledLayerCount = 1;
    info.ppEnabledLayerNames = &layer;
    info.pNext = sync_validation ? static_cast<void*>(&features) : &messenger;  // messages of creation too
  }
  info.enabledExtensionCount = uint32_t(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  check(vkCreateInstance(&info, nullptr, &instance), "vkCreateInstance (is the validation layer installed?)");
  instance_extensions = extensions;
  if (validation) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT"));
    check(create(instance, &messenger, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
  }

  // Physical device: the first GPU, else the CPU driver (lavapipe), unless one is named.
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(instance, &count, devices.data());
  auto pick = [&](bool gpu) {
    for (VkPhysicalDevice pd : devices) {
      VkPhysicalDeviceProperties p;
      vkGetPhysicalDeviceProperties(pd, &p);
      if (p.apiVersion < VK_API_VERSION_1_3 || (p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) == gpu) continue;
      name = p.deviceName;
      return pd;
    }
    return VkPhysicalDevice(VK_NULL_HANDLE);
  };
  if (options.device != "lavapipe") physical = pick(true);
  if (!physical && options.device != "gpu") physical = pick(false);
  if (!physical) throw std::runtime_error("no Vulkan 1.3 device of kind '" + options.device + "'");

  // What the shadow module needs: every required item, and the optional ones this device has.
  setup = std::make_unique<shadows::DeviceSetup>(physical, options.leave_out);
  if (!setup->missing().empty()) throw std::runtime_error(setup->missing());

  uint32_t families = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, nullptr);
  std::vector<VkQueueFamilyProperties> props(families);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, props.data());
  const VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  while (family < families && (props[family].queueFlags & want) != want) ++family;
  if (family == families) throw std::runtime_error(name + " has no graphics and compute queue");

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue_info.queueFamilyIndex = family;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;
  VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  device_info.pNext = setup->features();
  device_info.queueCreateInfoCount = 1;
  device_info.pQueueCreateInfos = &queue_info;
  device_info.enabledExtensionCount = setup->extension_count();
  device_info.ppEnabledExtensionNames = setup->extension_names();
  check(vkCreateDevice(physical, &device_info, nullptr, &device), "vkCreateDevice");
  vkGetDeviceQueue(device, family, 0, &queue);
}

Device::~Device() { release(); }

void Device::release() {
  if (device) vkDestroyDevice(device, nullptr);
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
    destroy(instance, messenger_, nullptr);
  }
  if (instance) vkDestroyInstance(instance, nullptr);
  device = VK_NULL_HANDLE;
  messenger_ = VK_NULL_HANDLE;
  instance = VK_NULL_HANDLE;
}

shadows::ContextDesc Device::context_desc(uint32_t frames_in_flight, const shadows::Settings& settings) const {
  shadows::ContextDesc desc;
  desc.instance = instance;
  desc.physical_device = physical;
  desc.device = device;
  desc.queue_family = family;
  desc.queue = queue;
  desc.get_instance_proc_addr = vkGetInstanceProcAddr;
  desc.get_device_proc_addr = vkGetDeviceProcAddr;
  desc.enabled_instance_extension_names = instance_extensions.data();
  desc.enabled_instance_extension_count = uint32_t(instance_extensions.size());
  setup->describe(desc);
  desc.frames_in_flight = frames_in_flight;
  desc.settings = settings;
  return desc;
}

uint32_t Device::memory_type(uint32_t type_bits, VkMemoryPropertyFlags flags) const {
  VkPhysicalDeviceMemoryProperties props;
  vkGetPhysicalDeviceMemoryProperties(physical, &props);
  for (uint32_t i = 0; i < props.memoryTypeCount; ++i)
    if ((type_bits & (1u << i)) && (props.memoryTypes[i].propertyFlags & flags) == flags) return i;
  throw std::runtime_error("no memory type with flags " + std::to_string(flags));
}

Buffer make_buffer(const Device& d, VkDeviceSize size, VkBufferUsageFlags usage) {
  Buffer b;
  b.size = size;
  b.usage = usage;
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size;
  info.usage = usage;
  check(vkCreateBuffer(d.device, &info, nullptr, &b.buffer), "vkCreateBuffer");
  try {
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(d.device, b.buffer, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex =
        d.memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    check(vkAllocateMemory(d.device, &alloc, nullptr, &b.memory), "vkAllocateMemory");
    check(vkBindBufferMemory(d.device, b.buffer, b.memory, 0), "vkBindBufferMemory");
    check(vkMapMemory(d.device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
  } catch (...) {
    destroy(d, b);  // the buffer (and its memory, if made) with the error
    throw;
  }
  return b;
}

void destroy(const Device& d, Buffer& b) {
  vkDestroyBuffer(d.device, b.buffer, nullptr);
  vkFreeMemory(d.device, b.memory, nullptr);
  b = {};
}

Image make_image(const Device& d, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage) {
  Image i;
  i.format = format;
  i.extent = extent;
  i.usage = usage;
  const bool depth = format == VK_FORMAT_D24_UNORM_S8_UINT || format == VK_FORMAT_D32_SFLOAT ||
                     format == VK_FORMAT_D32_SFLOAT_S8_UINT || format == VK_FORMAT_D16_UNORM;
  i.aspect = depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {extent.width, extent.height, 1};
  info.mipLevels = info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = usage;
  check(vkCreateImage(d.device, &info, nullptr, &i.image), "vkCreateImage");
  try {
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(d.device, i.image, &req);
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = d.memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    check(vkAllocateMemory(d.device, &alloc, nullptr, &i.memory), "vkAllocateMemory");
    check(vkBindImageMemory(d.device, i.image, i.memory, 0), "vkBindImageMemory");
    // Depth/stencil: the view holds the depth aspect only (what the module samples).
    VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view.image = i.image;
    view.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view.format = format;
    view.subresourceRange = {i.aspect, 0, 1, 0, 1};
    check(vkCreateImageView(d.device, &view, nullptr, &i.view), "vkCreateImageView");
  } catch (...) {
    destroy(d, i);  // what was made of it, with the error
    throw;
  }
  return i;
}

void destroy(const Device& d, Image& i) {
  vkDestroyImageView(d.device, i.view, nullptr);
  vkDestroyImage(d.device, i.image, nullptr);
  vkFreeMemory(d.device, i.memory, nullptr);
  i = {};
}

void image_barrier(VkCommandBuffer cmd, const Image& image, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                   VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access, VkImageLayout from, VkImageLayout to) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image.image;
  // A depth/stencil image changes layout in both aspects at once.
  const VkImageAspectFlags aspect =
      image.format == VK_FORMAT_D24_UNORM_S8_UINT || image.format == VK_FORMAT_D32_SFLOAT_S8_UINT
          ? VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT
          : image.aspect;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

}  // namespace vulkan_host
