#include "engine/gpu/context.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <type_traits>

namespace engine::gpu {

namespace {

std::mutex g_message_mutex;

bool env_flag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::strcmp(v, "0") != 0;
}

bool has_extension(const std::vector<VkExtensionProperties>& list, const char* name) {
  return std::any_of(list.begin(), list.end(),
                     [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

std::vector<VkExtensionProperties> device_extensions(VkPhysicalDevice pd) {
  uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> out(count);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &count, out.data());
  return out;
}

const char* device_type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

bool is_gpu(VkPhysicalDeviceType t) {
  return t == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU || t == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ||
         t == VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU;
}

std::vector<std::string> split_list(const char* text) {
  std::vector<std::string> out;
  std::string item;
  for (const char* c = text; c && *c; ++c) {
    if (*c == ',') {
      if (!item.empty()) out.push_back(item);
      item.clear();
    } else if (*c != ' ') {
      item += *c;
    }
  }
  if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

const std::vector<std::string>& maskable_feature_names() {
  static const std::vector<std::string> names = {"conservative_rasterization", "geometry_shader",
                                                 "fragment_shader_barycentric", "subgroup_arithmetic"};
  return names;
}

VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                              VkDebugUtilsMessageTypeFlagsEXT,
                                              const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* ctx = static_cast<Context*>(user);
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    ctx->validation_messages_++;
    std::lock_guard lock(g_message_mutex);
    ctx->message_log_.emplace_back(data->pMessage ? data->pMessage : "(no message)");
    std::fprintf(stderr, "[vulkan] %s\n", data->pMessage ? data->pMessage : "");
  }
  return VK_FALSE;
}

std::vector<std::string> Context::validation_messages() const {
  std::lock_guard lock(g_message_mutex);
  return message_log_;
}

Context::Context(const ContextOptions& options) {
  masked_features_ = options.masked_features;
  for (const auto& name : split_list(std::getenv("ENGINE_MASK_FEATURES"))) masked_features_.push_back(name);
  const auto& known = maskable_feature_names();
  for (const auto& name : masked_features_) {
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw VulkanError("cannot mask feature '" + name + "': expected one of " + list);
    }
  }
  create_instance(options);
  pick_physical_device(options);
  create_device(options);
}

Context::~Context() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    vkDestroyCommandPool(device_, command_pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

void Context::create_instance(const ContextOptions& options) {
#ifndef NDEBUG
  const bool debug_build = true;
#else
  const bool debug_build = false;
#endif
  // Synchronization validation implies the layer (one variable for test runners that set only one).
  bool want_validation = options.validation || env_flag("ENGINE_VALIDATION") || env_flag("ENGINE_SYNC_VALIDATION") ||
                         debug_build;

  uint32_t layer_count = 0;
  vkEnumerateInstanceLayerProperties(&layer_count, nullptr);
  std::vector<VkLayerProperties> layers(layer_count);
  vkEnumerateInstanceLayerProperties(&layer_count, layers.data());
  const char* kValidation = "VK_LAYER_KHRONOS_validation";
  bool layer_present = std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) {
    return std::strcmp(l.layerName, kValidation) == 0;
  });
  if (want_validation && !layer_present) {
    std::fprintf(stderr, "warning: validation requested but VK_LAYER_KHRONOS_validation is not installed; "
                         "continuing without it (install vulkan-validationlayers)\n");
  }
  validation_enabled_ = want_validation && layer_present;

  uint32_t ext_count = 0;
  vkEnumerateInstanceExtensionProperties(nullptr, &ext_count, nullptr);
  std::vector<VkExtensionProperties> available(ext_count);
  vkEnumerateInstanceExtensionProperties(nullptr, &ext_count, available.data());

  std::vector<const char*> extensions = options.instance_extensions;
  for (const char* e : extensions) {
    if (!has_extension(available, e))
      throw VulkanError(std::string("the Vulkan instance lacks extension ") + e + " needed for the window");
  }
  debug_utils_ = has_extension(available, VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  if (debug_utils_) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = options.application_name.c_str();
  app.pEngineName = "shadow_engine";
  app.apiVersion = VK_API_VERSION_1_3;

  VkDebugUtilsMessengerCreateInfoEXT messenger_info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messenger_info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                   VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messenger_info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  messenger_info.pfnUserCallback = debug_callback;
  messenger_info.pUserData = this;

  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  // Synchronization validation: the layer also reports hazards between commands (missing barriers).
  sync_validation_enabled_ = validation_enabled_ && (options.sync_validation || env_flag("ENGINE_SYNC_VALIDATION"));
  const VkValidationFeatureEnableEXT sync_enable = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT validation_features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  validation_features.enabledValidationFeatureCount = 1;
  validation_features.pEnabledValidationFeatures = &sync_enable;
  if (validation_enabled_) {
    info.enabledLayerCount = 1;
    info.ppEnabledLayerNames = &kValidation;
    if (debug_utils_) info.pNext = &messenger_info;  // also catches instance creation messages
    if (sync_validation_enabled_) {
      uint32_t layer_ext_count = 0;
      vkEnumerateInstanceExtensionProperties(kValidation, &layer_ext_count, nullptr);
      std::vector<VkExtensionProperties> layer_extensions(layer_ext_count);
      vkEnumerateInstanceExtensionProperties(kValidation, &layer_ext_count, layer_extensions.data());
      if (!has_extension(layer_extensions, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME))
        throw VulkanError("synchronization validation requested but the validation layer lacks " 
                          VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
      extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
      info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
      info.ppEnabledExtensionNames = extensions.data();
      validation_features.pNext = info.pNext;
      info.pNext = &validation_features;
    }
  }
  VkResult r = vkCreateInstance(&info, nullptr, &instance_);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw VulkanError("no Vulkan 1.3 driver found (install mesa-vulkan-drivers for the CPU driver)");
  VK_CHECK(r);

  if (validation_enabled_ && debug_utils_) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (create) VK_CHECK(create(instance_, &messenger_info, nullptr, &messenger_));
  }
  if (debug_utils_) {
    set_object_name_ = reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(
        vkGetInstanceProcAddr(instance_, "vkSetDebugUtilsObjectNameEXT"));
    cmd_begin_label_ = reinterpret_cast<PFN_vkCmdBeginDebugUtilsLabelEXT>(
        vkGetInstanceProcAddr(instance_, "vkCmdBeginDebugUtilsLabelEXT"));
    cmd_end_label_ = reinterpret_cast<PFN_vkCmdEndDebugUtilsLabelEXT>(
        vkGetInstanceProcAddr(instance_, "vkCmdEndDebugUtilsLabelEXT"));
  }
}

void Context::pick_physical_device(const ContextOptions& options) {
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance_, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(instance_, &count, devices.data());
  if (devices.empty()) throw VulkanError("no Vulkan device found (install mesa-vulkan-drivers for lavapipe)");

  std::string listing;
  std::vector<VkPhysicalDeviceProperties> props(count);
  for (uint32_t i = 0; i < count; ++i) {
    vkGetPhysicalDeviceProperties(devices[i], &props[i]);
    listing += (i ? ", " : "") + std::to_string(i) + ": " + props[i].deviceName + " (" +
               device_type_name(props[i].deviceType) + ")";
  }
  auto usable = [&](uint32_t i) { return props[i].apiVersion >= VK_API_VERSION_1_3; };

  int chosen = -1;
  const std::string& want = options.device.empty() ? std::string(std::getenv("ENGINE_DEVICE") ? std::getenv("ENGINE_DEVICE") : "")
                                                   : options.device;
  if (want.empty() || want == "auto") {
    int best_rank = -1;
    for (uint32_t i = 0; i < count; ++i) {
      if (!usable(i)) continue;
      int rank = props[i].deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? 4
                 : props[i].deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? 3
                 : props[i].deviceType == VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU    ? 2
                                                                                  : 1;
      if (rank > best_rank) best_rank = rank, chosen = static_cast<int>(i);
    }
  } else if (want == "gpu") {
    for (uint32_t i = 0; i < count && chosen < 0; ++i)
      if (usable(i) && is_gpu(props[i].deviceType)) chosen = static_cast<int>(i);
    if (chosen < 0) throw VulkanError("--device gpu: no Vulkan 1.3 GPU found; devices: " + listing);
  } else if (want == "lavapipe" || want == "cpu") {
    for (uint32_t i = 0; i < count && chosen < 0; ++i)
      if (usable(i) && props[i].deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) chosen = static_cast<int>(i);
    if (chosen < 0) throw VulkanError("--device lavapipe: Mesa's CPU driver is not installed; devices: " + listing);
  } else {
    char* end = nullptr;
    long index = std::strtol(want.c_str(), &end, 10);
    if (!end || *end || index < 0 || index >= static_cast<long>(count))
      throw VulkanError("--device '" + want + "': expected gpu, lavapipe or an index; devices: " + listing);
    chosen = static_cast<int>(index);
    if (!usable(index)) throw VulkanError("device " + want + " does not support Vulkan 1.3");
  }
  if (chosen < 0) throw VulkanError("no device supports Vulkan 1.3; devices: " + listing);
  physical_device_ = devices[chosen];
  properties_ = props[chosen];
  vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_properties_);
}

void Context::create_device(const ContextOptions& options) {
  const auto available = device_extensions(physical_device_);
  std::vector<const char*> extensions;
  auto require = [&](const char* name) {
    if (!has_extension(available, name))
      throw VulkanError(std::string("device ") + properties_.deviceName + " lacks required extension " + name);
    extensions.push_back(name);
  };
  require(VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);
  if (options.swapchain) require(VK_KHR_SWAPCHAIN_EXTENSION_NAME);

  // Optional features: enabled when present, recorded in features_.
  VkPhysicalDeviceFragmentShaderBarycentricFeaturesKHR bary_features{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FRAGMENT_SHADER_BARYCENTRIC_FEATURES_KHR};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f2.pNext = &f12;
  f12.pNext = &f13;
  const bool has_bary = has_extension(available, VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME);
  if (has_bary) f13.pNext = &bary_features;
  // Ray tracing feature queries, chained only for the extensions the device lists.
  VkPhysicalDeviceAccelerationStructureFeaturesKHR as_features{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR};
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR rtp_features{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR};
  VkPhysicalDeviceRayQueryFeaturesKHR rq_features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR};
  const bool has_as = has_extension(available, VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME) &&
                      has_extension(available, VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME);
  const bool has_rtp = has_as && has_extension(available, VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME);
  const bool has_rq = has_as && has_extension(available, VK_KHR_RAY_QUERY_EXTENSION_NAME);
  {
    void** tail = has_bary ? &bary_features.pNext : &f13.pNext;
    auto append = [&](auto& s) {
      *tail = &s;
      tail = &s.pNext;
    };
    if (has_as) append(as_features);
    if (has_rtp) append(rtp_features);
    if (has_rq) append(rq_features);
  }
  vkGetPhysicalDeviceFeatures2(physical_device_, &f2);

  if (!f13.dynamicRendering || !f13.synchronization2)
    throw VulkanError(std::string("device ") + properties_.deviceName + " lacks dynamic rendering or synchronization2");

  VkPhysicalDeviceFeatures2 enable2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  VkPhysicalDeviceVulkan12Features enable12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceVulkan13Features enable13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceFragmentShaderBarycentricFeaturesKHR enable_bary{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FRAGMENT_SHADER_BARYCENTRIC_FEATURES_KHR};
  enable2.pNext = &enable12;
  enable12.pNext = &enable13;
  enable13.dynamicRendering = VK_TRUE;
  enable13.synchronization2 = VK_TRUE;
  enable13.maintenance4 = f13.maintenance4;
  enable12.scalarBlockLayout = f12.scalarBlockLayout;
  enable12.hostQueryReset = f12.hostQueryReset;
  enable12.shaderInt8 = f12.shaderInt8;
  enable12.storageBuffer8BitAccess = f12.storageBuffer8BitAccess;
  enable2.features.geometryShader = f2.features.geometryShader;
  enable2.features.fragmentStoresAndAtomics = f2.features.fragmentStoresAndAtomics;
  enable2.features.vertexPipelineStoresAndAtomics = f2.features.vertexPipelineStoresAndAtomics;
  enable2.features.shaderInt64 = f2.features.shaderInt64;
  enable2.features.shaderStorageImageWriteWithoutFormat = f2.features.shaderStorageImageWriteWithoutFormat;
  enable2.features.depthClamp = f2.features.depthClamp;
  enable2.features.fillModeNonSolid = f2.features.fillModeNonSolid;
  enable2.features.independentBlend = f2.features.independentBlend;
  enable2.features.pipelineStatisticsQuery = f2.features.pipelineStatisticsQuery;

  auto masked = [&](const char* name) {
    return std::find(masked_features_.begin(), masked_features_.end(), name) != masked_features_.end();
  };
  // A masked feature is neither enabled nor recorded, so using it anyway is a validation error.
  if (masked("geometry_shader")) f2.features.geometryShader = VK_FALSE;
  enable2.features.geometryShader = f2.features.geometryShader;
  features_.geometry_shader = f2.features.geometryShader;
  features_.depth_clamp = f2.features.depthClamp;
  features_.fragment_stores_and_atomics = f2.features.fragmentStoresAndAtomics;
  features_.vertex_stores_and_atomics = f2.features.vertexPipelineStoresAndAtomics;
  features_.shader_int64 = f2.features.shaderInt64;

  if (has_bary && bary_features.fragmentShaderBarycentric && !masked("fragment_shader_barycentric")) {
    extensions.push_back(VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME);
    enable_bary.fragmentShaderBarycentric = VK_TRUE;
    enable13.pNext = &enable_bary;
    features_.fragment_shader_barycentric = true;
  }
  if (has_extension(available, VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME) && !masked("conservative_rasterization")) {
    extensions.push_back(VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME);
    VkPhysicalDeviceConservativeRasterizationPropertiesEXT cprops{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_CONSERVATIVE_RASTERIZATION_PROPERTIES_EXT};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    p2.pNext = &cprops;
    vkGetPhysicalDeviceProperties2(physical_device_, &p2);
    features_.conservative_rasterization = true;
    features_.conservative_underestimation = cprops.primitiveUnderestimation;
    features_.fully_covered_fragment_input = cprops.fullyCoveredFragmentShaderInputVariable;
    features_.conservative_overestimation_size = cprops.maxExtraPrimitiveOverestimationSize;
  }
  features_.max_storage_buffer_range = properties_.limits.maxStorageBufferRange;
  // Ray tracing: acceleration structures need buffer device addresses and deferred host operations;
  // the technique traces through the pipeline (ray query alone is recorded, not used yet).
  VkPhysicalDeviceAccelerationStructureFeaturesKHR enable_as{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR};
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR enable_rtp{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR};
  VkPhysicalDeviceRayQueryFeaturesKHR enable_rq{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR};
  const bool as_usable = has_as && as_features.accelerationStructure && f12.bufferDeviceAddress;
  const bool rtp_usable = as_usable && has_rtp && rtp_features.rayTracingPipeline;
  const bool rq_usable = as_usable && has_rq && rq_features.rayQuery;
  if (as_usable && (rtp_usable || rq_usable)) {
    extensions.push_back(VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME);
    extensions.push_back(VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME);
    enable12.bufferDeviceAddress = VK_TRUE;
    enable_as.accelerationStructure = VK_TRUE;
    void** tail = features_.fragment_shader_barycentric ? &enable_bary.pNext : &enable13.pNext;
    *tail = &enable_as;
    tail = &enable_as.pNext;
    if (rtp_usable) {
      extensions.push_back(VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME);
      enable_rtp.rayTracingPipeline = VK_TRUE;
      *tail = &enable_rtp;
      tail = &enable_rtp.pNext;
    }
    if (rq_usable) {
      extensions.push_back(VK_KHR_RAY_QUERY_EXTENSION_NAME);
      enable_rq.rayQuery = VK_TRUE;
      *tail = &enable_rq;
    }
    features_.acceleration_structure = true;
    features_.buffer_device_address = true;
    features_.ray_tracing_pipeline = rtp_usable;
    features_.ray_query = rq_usable;
    VkPhysicalDeviceRayTracingPipelinePropertiesKHR rt_props{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_PROPERTIES_KHR};
    VkPhysicalDeviceAccelerationStructurePropertiesKHR as_props{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR};
    as_props.pNext = rtp_usable ? &rt_props : nullptr;
    VkPhysicalDeviceProperties2 rp2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    rp2.pNext = &as_props;
    vkGetPhysicalDeviceProperties2(physical_device_, &rp2);
    features_.scratch_offset_alignment = as_props.minAccelerationStructureScratchOffsetAlignment;
    if (rtp_usable) {
      features_.shader_group_handle_size = rt_props.shaderGroupHandleSize;
      features_.shader_group_handle_alignment = rt_props.shaderGroupHandleAlignment;
      features_.shader_group_base_alignment = rt_props.shaderGroupBaseAlignment;
    }
  }
  if (!features_.ray_tracing_pipeline) {
    features_.ray_tracing_missing =
        !has_as ? std::string("device ") + properties_.deviceName + " lacks " VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME
        : !as_usable ? std::string("device ") + properties_.deviceName + " lacks the accelerationStructure/bufferDeviceAddress features"
        : std::string("device ") + properties_.deviceName + " lacks " VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME;
  }

  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceMaintenance3Properties maintenance3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
  subgroup.pNext = &driver;
  driver.pNext = &maintenance3;
  VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  p2.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(physical_device_, &p2);
  features_.subgroup_size = subgroup.subgroupSize;
  const VkSubgroupFeatureFlags needed_ops = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;
  const VkShaderStageFlags needed_stages = VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  features_.subgroup_arithmetic_compute_fragment = (subgroup.supportedOperations & needed_ops) == needed_ops &&
                                                   (subgroup.supportedStages & needed_stages) == needed_stages &&
                                                   !masked("subgroup_arithmetic");
  driver_description_ = std::string(driver.driverName) + " " + driver.driverInfo;
  max_allocation_size_ = maintenance3.maxMemoryAllocationSize;

  uint32_t family_count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &family_count, nullptr);
  std::vector<VkQueueFamilyProperties> families(family_count);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &family_count, families.data());
  bool found = false;
  for (uint32_t i = 0; i < family_count; ++i) {
    if ((families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
      queue_family_ = i;
      found = true;
      features_.timestamps = families[i].timestampValidBits > 0;
      break;
    }
  }
  if (!found) throw VulkanError(std::string("device ") + properties_.deviceName + " has no graphics+compute queue");
  features_.timestamp_period_ns = properties_.limits.timestampPeriod;

  float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue_info.queueFamilyIndex = queue_family_;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;

  VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  info.pNext = &enable2;
  info.queueCreateInfoCount = 1;
  info.pQueueCreateInfos = &queue_info;
  info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  VK_CHECK(vkCreateDevice(physical_device_, &info, nullptr, &device_));
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

  cmd_push_descriptor_set =
      reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(vkGetDeviceProcAddr(device_, "vkCmdPushDescriptorSetKHR"));
  if (features_.acceleration_structure) {
    auto load = [&](auto& fn, const char* name) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(vkGetDeviceProcAddr(device_, name));
      if (!fn) throw VulkanError(std::string("device ") + properties_.deviceName + " did not return " + name);
    };
    load(rt.create_acceleration_structure, "vkCreateAccelerationStructureKHR");
    load(rt.destroy_acceleration_structure, "vkDestroyAccelerationStructureKHR");
    load(rt.get_build_sizes, "vkGetAccelerationStructureBuildSizesKHR");
    load(rt.get_acceleration_structure_address, "vkGetAccelerationStructureDeviceAddressKHR");
    load(rt.cmd_build_acceleration_structures, "vkCmdBuildAccelerationStructuresKHR");
    if (features_.ray_tracing_pipeline) {
      load(rt.create_ray_tracing_pipelines, "vkCreateRayTracingPipelinesKHR");
      load(rt.get_shader_group_handles, "vkGetRayTracingShaderGroupHandlesKHR");
      load(rt.cmd_trace_rays, "vkCmdTraceRaysKHR");
    }
  }

  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool_info.queueFamilyIndex = queue_family_;
  VK_CHECK(vkCreateCommandPool(device_, &pool_info, nullptr, &command_pool_));
  set_name(device_, VK_OBJECT_TYPE_DEVICE, "engine device");
}

void Context::track_allocation(VkDeviceMemory memory, const std::string& name, VkDeviceSize bytes) const {
  std::lock_guard lock(g_message_mutex);
  allocations_[memory] = {name, bytes};
}

void Context::untrack_allocation(VkDeviceMemory memory) const {
  std::lock_guard lock(g_message_mutex);
  allocations_.erase(memory);
}

std::vector<Context::Allocation> Context::allocations() const {
  std::lock_guard lock(g_message_mutex);
  std::vector<Allocation> out;
  out.reserve(allocations_.size());
  for (const auto& [memory, a] : allocations_) out.push_back(a);
  return out;
}

uint32_t Context::find_memory_type(uint32_t type_bits, VkMemoryPropertyFlags properties) const {
  for (uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i) {
    if ((type_bits & (1u << i)) && (memory_properties_.memoryTypes[i].propertyFlags & properties) == properties)
      return i;
  }
  throw VulkanError("no memory type with the requested properties");
}

uint32_t Context::live_allocation_count() const {
  std::lock_guard lock(g_message_mutex);
  return static_cast<uint32_t>(allocations_.size());
}

VkDeviceMemory Context::allocate_memory(const VkMemoryAllocateInfo& info, const std::string& what) const {
  if (max_allocation_size_ && info.allocationSize > max_allocation_size_)
    throw VulkanError(what + " needs " + std::to_string(info.allocationSize) + " bytes, more than the " +
                      std::to_string(max_allocation_size_) + " bytes " + properties_.deviceName +
                      " allocates at once");
  VkDeviceMemory memory = VK_NULL_HANDLE;
  const VkResult r = vkAllocateMemory(device_, &info, nullptr, &memory);
  if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
    throw VulkanError(what + " needs " + std::to_string(info.allocationSize) + " bytes, and " +
                      properties_.deviceName + " is out of memory (" + vk_result_name(r) + ")");
  VK_CHECK(r);
  return memory;
}

void Context::free_memory(VkDeviceMemory memory) const {
  if (!memory) return;
  vkFreeMemory(device_, memory, nullptr);
}

void Context::immediate_submit(const std::function<void(VkCommandBuffer)>& record) const {
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = command_pool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cmd;
  VK_CHECK(vkAllocateCommandBuffers(device_, &alloc, &cmd));
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  VK_CHECK(vkCreateFence(device_, &fence_info, nullptr, &fence));
  record_submit_wait(cmd, fence, record);
  vkDestroyFence(device_, fence, nullptr);
  vkFreeCommandBuffers(device_, command_pool_, 1, &cmd);
}

void Context::record_submit_wait(VkCommandBuffer cmd, VkFence fence,
                                 const std::function<void(VkCommandBuffer)>& record) const {
  VK_CHECK(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_CHECK(vkBeginCommandBuffer(cmd, &begin));
  record(cmd);
  VK_CHECK(vkEndCommandBuffer(cmd));
  VK_CHECK(vkResetFences(device_, 1, &fence));
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  VK_CHECK(vkQueueSubmit(queue_, 1, &submit, fence));
  VK_CHECK(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX));
}

void Context::set_name(VkObjectType type, uint64_t handle, const std::string& name) const {
  if (!set_object_name_ || !handle) return;
  VkDebugUtilsObjectNameInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT};
  info.objectType = type;
  info.objectHandle = handle;
  info.pObjectName = name.c_str();
  set_object_name_(device_, &info);
}

void Context::begin_label(VkCommandBuffer cmd, const char* name) const {
  if (!cmd_begin_label_) return;
  VkDebugUtilsLabelEXT label{VK_STRUCTURE_TYPE_DEBUG_UTILS_LABEL_EXT};
  label.pLabelName = name;
  cmd_begin_label_(cmd, &label);
}

void Context::end_label(VkCommandBuffer cmd) const {
  if (cmd_end_label_) cmd_end_label_(cmd);
}

}  // namespace engine::gpu
