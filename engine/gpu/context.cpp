#include "gpu/context.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <type_traits>

namespace engine::gpu {

namespace {

// The subgroup operations DeviceFeatures::subgroup_arithmetic_compute_fragment stands for.
constexpr VkSubgroupFeatureFlags kSubgroupOps =
    VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT;

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

// Every feature structure the engine reads or enables, linked as one pNext chain. Not copyable: the
// chain points into itself.
struct FeatureChain {
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceFragmentShaderBarycentricFeaturesKHR bary{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FRAGMENT_SHADER_BARYCENTRIC_FEATURES_KHR};
  VkPhysicalDeviceAccelerationStructureFeaturesKHR as{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR};
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR rtp{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR};
  VkPhysicalDeviceRayQueryFeaturesKHR rq{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR};

  FeatureChain() = default;
  FeatureChain(const FeatureChain&) = delete;
  FeatureChain& operator=(const FeatureChain&) = delete;

  // Links f2 -> 1.2 -> 1.3, then the structures of the extensions `has` accepts: a query may chain only
  // structures of extensions the device lists, and vkCreateDevice only those of enabled extensions.
  template <typename Has>
  void link(const Has& has) {
    f2.pNext = &f12;
    f12.pNext = &f13;
    void** tail = &f13.pNext;
    auto append = [&](auto& s, const char* extension) {
      s.pNext = nullptr;
      if (!has(extension)) return;
      *tail = &s;
      tail = &s.pNext;
    };
    *tail = nullptr;
    append(bary, VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME);
    append(as, VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME);
    append(rtp, VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME);
    append(rq, VK_KHR_RAY_QUERY_EXTENSION_NAME);
  }
};

namespace {

// Ray tracing needs acceleration structures (with deferred host operations and buffer device
// addresses) and a way to trace: the pipeline or ray queries. The group is enabled whole or not at all.
enum class RtGroup { None, Base, Pipeline, Query };

struct RayTracingSupport {
  bool extensions = false;  // acceleration structure + deferred host operations
  bool base = false;        // ... and the accelerationStructure, bufferDeviceAddress features
  bool pipeline = false;
  bool query = false;
};

template <typename Has>
RayTracingSupport ray_tracing_support(const FeatureChain& c, const Has& has) {
  RayTracingSupport r;
  r.extensions = has(VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME) && has(VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME);
  r.base = r.extensions && c.as.accelerationStructure && c.f12.bufferDeviceAddress;
  r.pipeline = r.base && has(VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME) && c.rtp.rayTracingPipeline;
  r.query = r.base && has(VK_KHR_RAY_QUERY_EXTENSION_NAME) && c.rq.rayQuery;
  return r;
}

bool group_usable(RtGroup group, const RayTracingSupport& rt) {
  switch (group) {
    case RtGroup::Base: return rt.pipeline || rt.query;  // acceleration structures alone are of no use
    case RtGroup::Pipeline: return rt.pipeline;
    case RtGroup::Query: return rt.query;
    default: return true;
  }
}

// One feature bit the engine enables: required ones always (the device must have them), optional ones
// where the device has them. The owning context, the adopting one and device_requirements() all read
// this table.
struct FeatureBit {
  const char* name;                      // the Vulkan member name
  VkBool32* (*field)(FeatureChain&);
  bool required = false;
  const char* extension = nullptr;       // the extension whose structure holds the bit
  const char* mask = nullptr;            // the maskable feature name that leaves it off
  RtGroup group = RtGroup::None;
};

#define ENGINE_FEATURE_BIT(path, member) .name = #member, .field = [](FeatureChain& c) { return &c.path.member; }
const FeatureBit kFeatureBits[] = {
    // Every barrier is a vkCmdPipelineBarrier2 and every pass renders with vkCmdBeginRendering.
    {ENGINE_FEATURE_BIT(f13, synchronization2), .required = true},
    {ENGINE_FEATURE_BIT(f13, dynamicRendering), .required = true},
    {ENGINE_FEATURE_BIT(f13, maintenance4)},
    {ENGINE_FEATURE_BIT(f12, scalarBlockLayout)},
    {ENGINE_FEATURE_BIT(f12, hostQueryReset)},
    {ENGINE_FEATURE_BIT(f12, shaderInt8)},
    {ENGINE_FEATURE_BIT(f12, storageBuffer8BitAccess)},
    {ENGINE_FEATURE_BIT(f2.features, geometryShader), .mask = "geometry_shader"},
    {ENGINE_FEATURE_BIT(f2.features, fragmentStoresAndAtomics)},
    {ENGINE_FEATURE_BIT(f2.features, vertexPipelineStoresAndAtomics)},
    {ENGINE_FEATURE_BIT(f2.features, shaderInt64)},
    {ENGINE_FEATURE_BIT(f2.features, shaderStorageImageWriteWithoutFormat)},
    {ENGINE_FEATURE_BIT(f2.features, depthClamp)},
    {ENGINE_FEATURE_BIT(f2.features, fillModeNonSolid)},
    {ENGINE_FEATURE_BIT(f2.features, independentBlend)},
    {ENGINE_FEATURE_BIT(f2.features, pipelineStatisticsQuery)},
    {ENGINE_FEATURE_BIT(bary, fragmentShaderBarycentric), .extension = VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME,
     .mask = "fragment_shader_barycentric"},
    {ENGINE_FEATURE_BIT(f12, bufferDeviceAddress), .group = RtGroup::Base},
    {ENGINE_FEATURE_BIT(as, accelerationStructure), .extension = VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME,
     .group = RtGroup::Base},
    {ENGINE_FEATURE_BIT(rtp, rayTracingPipeline), .extension = VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME,
     .group = RtGroup::Pipeline},
    {ENGINE_FEATURE_BIT(rq, rayQuery), .extension = VK_KHR_RAY_QUERY_EXTENSION_NAME, .group = RtGroup::Query},
};
#undef ENGINE_FEATURE_BIT

VkBool32 bit_of(const FeatureChain& c, const FeatureBit& bit) { return *bit.field(const_cast<FeatureChain&>(c)); }

// The device extensions the engine enables, by the same rule as the feature bits.
struct DeviceExtension {
  const char* name;
  bool required = false;
  const char* mask = nullptr;
  RtGroup group = RtGroup::None;
};
const DeviceExtension kDeviceExtensions[] = {
    // Every pipeline layout is a push descriptor layout (DescriptorWriter::push).
    {.name = VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME, .required = true},
    {.name = VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME, .mask = "conservative_rasterization"},
    {.name = VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME, .mask = "fragment_shader_barycentric"},
    {.name = VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME, .group = RtGroup::Base},
    {.name = VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME, .group = RtGroup::Base},
    {.name = VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME, .group = RtGroup::Pipeline},
    {.name = VK_KHR_RAY_QUERY_EXTENSION_NAME, .group = RtGroup::Query},
};

bool contains(const std::vector<std::string>& list, const char* name) {
  return std::find(list.begin(), list.end(), name) != list.end();
}

}  // namespace

// What a physical device offers: its extensions and every feature structure of them, queried once.
struct DeviceSupport {
  std::vector<VkExtensionProperties> extensions;
  FeatureChain features;

  explicit DeviceSupport(VkPhysicalDevice pd) : extensions(device_extensions(pd)) {
    features.link([&](const char* name) { return has(name); });
    vkGetPhysicalDeviceFeatures2(pd, &features.f2);
  }
  bool has(const char* name) const { return has_extension(extensions, name); }
  RayTracingSupport ray_tracing() const {
    return ray_tracing_support(features, [&](const char* name) { return has(name); });
  }
  // An extension is worth enabling only with the features it brings (its structure's bits).
  bool extension_usable(const char* name) const {
    if (!has(name)) return false;
    return std::none_of(std::begin(kFeatureBits), std::end(kFeatureBits), [&](const FeatureBit& bit) {
      return bit.extension && std::strcmp(bit.extension, name) == 0 && !bit_of(features, bit);
    });
  }
  // Whether an optional entry of the tables is enabled: the device has it (and its extension), the
  // whole ray tracing group it belongs to is usable, and it is not masked.
  bool optional_usable(const char* extension, const char* mask, RtGroup group,
                       const std::vector<std::string>& masked) const {
    if (mask && contains(masked, mask)) return false;
    if (extension && !extension_usable(extension)) return false;
    return group_usable(group, ray_tracing());
  }
  bool wanted(const FeatureBit& bit, const std::vector<std::string>& masked) const {
    return bit.required || (bit_of(features, bit) && optional_usable(bit.extension, bit.mask, bit.group, masked));
  }
  bool wanted(const DeviceExtension& e, const std::vector<std::string>& masked) const {
    return e.required || optional_usable(e.name, e.mask, e.group, masked);
  }
};

DeviceRequirements device_requirements(VkPhysicalDevice physical_device) {
  const DeviceSupport support(physical_device);
  DeviceRequirements out;
  for (const auto& e : kDeviceExtensions) {
    if (e.required) out.required_device_extensions.emplace_back(e.name);
    else if (support.wanted(e, {})) out.optional_device_extensions.emplace_back(e.name);
  }
  for (const auto& bit : kFeatureBits) {
    if (bit.required) out.required_features.emplace_back(bit.name);
    else if (support.wanted(bit, {})) out.optional_features.emplace_back(bit.name);
  }
  return out;
}

namespace {

template <typename T>
void copy_keeping_next(T& dst, const VkBaseInStructure* src) {
  void* next = dst.pNext;
  dst = *reinterpret_cast<const T*>(src);
  dst.pNext = next;
}

template <typename T>
VkBool32 member_of(const VkBaseInStructure* s, VkBool32 T::*member) {
  return reinterpret_cast<const T*>(s)->*member;
}

// Reads the host's vkCreateDevice chain: the bits the engine reads, whether the host gave them in the
// Vulkan 1.2/1.3 structures or in the single-feature structures those promoted.
void read_host_chain(const VkPhysicalDeviceFeatures2* root, FeatureChain& out) {
  if (!root) return;
  out.f2.features = root->features;
  for (auto* s = static_cast<const VkBaseInStructure*>(root->pNext); s; s = s->pNext) {
    switch (s->sType) {
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES: copy_keeping_next(out.f12, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES: copy_keeping_next(out.f13, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FRAGMENT_SHADER_BARYCENTRIC_FEATURES_KHR: copy_keeping_next(out.bary, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR: copy_keeping_next(out.as, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR: copy_keeping_next(out.rtp, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR: copy_keeping_next(out.rq, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES:
        out.f13.synchronization2 |= member_of(s, &VkPhysicalDeviceSynchronization2Features::synchronization2);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES:
        out.f13.dynamicRendering |= member_of(s, &VkPhysicalDeviceDynamicRenderingFeatures::dynamicRendering);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_4_FEATURES:
        out.f13.maintenance4 |= member_of(s, &VkPhysicalDeviceMaintenance4Features::maintenance4);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_BUFFER_DEVICE_ADDRESS_FEATURES:
        out.f12.bufferDeviceAddress |= member_of(s, &VkPhysicalDeviceBufferDeviceAddressFeatures::bufferDeviceAddress);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SCALAR_BLOCK_LAYOUT_FEATURES:
        out.f12.scalarBlockLayout |= member_of(s, &VkPhysicalDeviceScalarBlockLayoutFeatures::scalarBlockLayout);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_HOST_QUERY_RESET_FEATURES:
        out.f12.hostQueryReset |= member_of(s, &VkPhysicalDeviceHostQueryResetFeatures::hostQueryReset);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_FLOAT16_INT8_FEATURES:
        out.f12.shaderInt8 |= member_of(s, &VkPhysicalDeviceShaderFloat16Int8Features::shaderInt8);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_8BIT_STORAGE_FEATURES:
        out.f12.storageBuffer8BitAccess |= member_of(s, &VkPhysicalDevice8BitStorageFeatures::storageBuffer8BitAccess);
        break;
      default: break;  // structures of bits the engine does not read (VkPhysicalDeviceVulkan11Features among them)
    }
  }
}

std::vector<VkQueueFamilyProperties> queue_families(VkPhysicalDevice pd) {
  uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, families.data());
  return families;
}

bool graphics_and_compute(const VkQueueFamilyProperties& family) {
  return (family.queueFlags & VK_QUEUE_GRAPHICS_BIT) && (family.queueFlags & VK_QUEUE_COMPUTE_BIT);
}

std::string version_text(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v));
}

// Warnings and errors of the validation layer, counted by debug_callback.
VkDebugUtilsMessengerCreateInfoEXT messenger_create_info(Context* ctx) {
  VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  info.pfnUserCallback = debug_callback;
  info.pUserData = ctx;
  return info;
}

}  // namespace

Context::Context(const ContextOptions& options) {
  set_masked_features(options.masked_features);
  create_instance(options);
  pick_physical_device(options);
  create_device(options);
}

Context::Context(const AdoptedDevice& host) : owns_device_(false) {
  // One line naming the field: the host's integration is wrong, not the engine.
  auto fail = [](const std::string& what) -> void { throw VulkanError("shadows: AdoptedDevice." + what); };
  if (!host.instance) fail("instance is VK_NULL_HANDLE");
  if (!host.physical_device) fail("physical_device is VK_NULL_HANDLE");
  if (!host.device) fail("device is VK_NULL_HANDLE");
  if (!host.queue) fail("queue is VK_NULL_HANDLE");
  if (!host.get_instance_proc_addr) fail("get_instance_proc_addr is null");
  if (!host.get_device_proc_addr) fail("get_device_proc_addr is null");
  if (host.api_version < VK_API_VERSION_1_3)
    fail("api_version is " + version_text(host.api_version) + ": the engine needs Vulkan 1.3");
  if (host.enabled_features && host.enabled_features->sType != VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2)
    fail("enabled_features is not a VkPhysicalDeviceFeatures2 (sType " +
         std::to_string(static_cast<int>(host.enabled_features->sType)) + ")");
  set_masked_features(host.masked_features);

  instance_ = host.instance;
  physical_device_ = host.physical_device;
  device_ = host.device;
  queue_ = host.queue;
  queue_family_ = host.queue_family;
  allocator_ = host.allocator;
  pipeline_cache_ = host.pipeline_cache;
  api_version_ = host.api_version;
  enabled_instance_extensions_ = host.enabled_instance_extensions;
  enabled_device_extensions_ = host.enabled_device_extensions;
  vkGetPhysicalDeviceProperties(physical_device_, &properties_);
  vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_properties_);
  const std::string device_text = std::string(" (") + properties_.deviceName + ")";
  if (properties_.apiVersion < VK_API_VERSION_1_3)
    fail("physical_device" + device_text + " supports Vulkan " + version_text(properties_.apiVersion) +
         ": the engine needs 1.3");
  const auto families = queue_families(physical_device_);
  if (queue_family_ >= families.size())
    fail("queue_family " + std::to_string(queue_family_) + " is out of range: the device has " +
         std::to_string(families.size()) + " queue families");
  if (!graphics_and_compute(families[queue_family_]))
    fail("queue_family " + std::to_string(queue_family_) + " has no graphics and compute");

  // Only what the device has AND the host enabled counts (the host cannot enable more, but a list
  // naming an extension twice or one the device lacks must not turn a path on).
  const DeviceSupport support(physical_device_);
  auto enabled_extension = [&](const char* name) {
    return support.has(name) && contains(enabled_device_extensions_, name);
  };
  for (const auto& e : kDeviceExtensions)
    if (e.required && !enabled_extension(e.name)) fail(std::string("enabled_device_extensions lacks ") + e.name);
  FeatureChain host_chain;
  read_host_chain(host.enabled_features, host_chain);
  enabled_chain_ = std::make_unique<FeatureChain>();
  for (const auto& bit : kFeatureBits) {
    const bool on = bit_of(support.features, bit) && bit_of(host_chain, bit) &&
                    (!bit.extension || enabled_extension(bit.extension));
    *bit.field(*enabled_chain_) = on ? VK_TRUE : VK_FALSE;
    if (bit.required && !on) fail(std::string("enabled_features lacks ") + bit.name);
  }
  enabled_chain_->link(enabled_extension);
  std::vector<std::string> usable_extensions;
  for (const auto& e : kDeviceExtensions)
    if (enabled_extension(e.name)) usable_extensions.emplace_back(e.name);
  detect_features(support, *enabled_chain_, usable_extensions);

  debug_utils_ = contains(enabled_instance_extensions_, VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  load_instance_functions(host.get_instance_proc_addr);
  load_device_functions(host.get_device_proc_addr);
  // Last: nothing after these throws, so nothing the context created can leak.
  if (host.count_validation_messages && debug_utils_) create_messenger();
  validation_enabled_ = messenger_ != VK_NULL_HANDLE;
  create_command_pool();
}

void Context::defer_release(std::function<void()> destroy) const {
  deferred_.push_back({recording_frame_, std::move(destroy)});
}

void Context::release_through(uint64_t completed_frame) const {
  std::vector<Deferred> kept;
  for (auto& d : deferred_) {
    if (d.frame <= completed_frame) d.destroy();
    else kept.push_back(std::move(d));
  }
  deferred_ = std::move(kept);
}

void Context::release_all_deferred() const {
  for (auto& d : deferred_) d.destroy();
  deferred_.clear();
}

Context::~Context() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    release_all_deferred();
    if (command_pool_) vkDestroyCommandPool(device_, command_pool_, allocator_);
    if (owns_device_) vkDestroyDevice(device_, allocator_);
  }
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        get_instance_proc_addr_(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, allocator_);
  }
  if (owns_device_ && instance_) vkDestroyInstance(instance_, allocator_);
}

const VkPhysicalDeviceFeatures2* Context::enabled_features() const {
  return enabled_chain_ ? &enabled_chain_->f2 : nullptr;
}

void Context::set_masked_features(const std::vector<std::string>& masked) {
  masked_features_ = masked;
  for (const auto& name : split_list(std::getenv("ENGINE_MASK_FEATURES"))) masked_features_.push_back(name);
  const auto& known = maskable_feature_names();
  for (const auto& name : masked_features_) {
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw VulkanError("cannot mask feature '" + name + "': expected one of " + list);
    }
  }
}

void Context::load_instance_functions(PFN_vkGetInstanceProcAddr get_instance_proc_addr) {
  get_instance_proc_addr_ = get_instance_proc_addr;
  if (!debug_utils_) return;
  set_object_name_ = reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(
      get_instance_proc_addr(instance_, "vkSetDebugUtilsObjectNameEXT"));
  cmd_begin_label_ = reinterpret_cast<PFN_vkCmdBeginDebugUtilsLabelEXT>(
      get_instance_proc_addr(instance_, "vkCmdBeginDebugUtilsLabelEXT"));
  cmd_end_label_ = reinterpret_cast<PFN_vkCmdEndDebugUtilsLabelEXT>(
      get_instance_proc_addr(instance_, "vkCmdEndDebugUtilsLabelEXT"));
}

void Context::create_messenger() {
  auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
      get_instance_proc_addr_(instance_, "vkCreateDebugUtilsMessengerEXT"));
  const auto info = messenger_create_info(this);
  if (create) VK_CHECK(create(instance_, &info, allocator_, &messenger_));
}

void Context::load_device_functions(PFN_vkGetDeviceProcAddr get_device_proc_addr) {
  auto load = [&](auto& fn, const char* name) {
    fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(get_device_proc_addr(device_, name));
    if (!fn) throw VulkanError(std::string("device ") + properties_.deviceName + " did not return " + name);
  };
  load(cmd_push_descriptor_set, "vkCmdPushDescriptorSetKHR");
  if (features_.acceleration_structure) {
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
}

void Context::create_command_pool() {
  // Setup uploads and readbacks (immediate_submit) reuse their command buffers.
  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool_info.queueFamilyIndex = queue_family_;
  VK_CHECK(vkCreateCommandPool(device_, &pool_info, allocator_, &command_pool_));
}

// features_ from what is enabled (`enabled`, `extensions`), with the device's properties; `device`
// only words ray_tracing_missing (what the device lacks, or that it was not enabled).
void Context::detect_features(const DeviceSupport& device, const FeatureChain& enabled,
                              const std::vector<std::string>& extensions) {
  auto has = [&](const char* name) { return contains(extensions, name); };
  auto masked = [&](const char* name) { return contains(masked_features_, name); };
  const VkPhysicalDeviceFeatures& core = enabled.f2.features;
  features_.geometry_shader = core.geometryShader && !masked("geometry_shader");
  features_.depth_clamp = core.depthClamp;
  features_.fragment_stores_and_atomics = core.fragmentStoresAndAtomics;
  features_.vertex_stores_and_atomics = core.vertexPipelineStoresAndAtomics;
  features_.shader_int64 = core.shaderInt64;
  features_.fragment_shader_barycentric = has(VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME) &&
                                          enabled.bary.fragmentShaderBarycentric &&
                                          !masked("fragment_shader_barycentric");
  if (has(VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME) && !masked("conservative_rasterization")) {
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

  // The technique traces through the pipeline (ray query alone is recorded, not used yet).
  const RayTracingSupport rt_enabled = ray_tracing_support(enabled, has);
  features_.acceleration_structure = rt_enabled.pipeline || rt_enabled.query;
  features_.ray_tracing_pipeline = rt_enabled.pipeline;
  features_.ray_query = rt_enabled.query;
  features_.buffer_device_address = enabled.f12.bufferDeviceAddress;
  if (features_.acceleration_structure) {
    VkPhysicalDeviceRayTracingPipelinePropertiesKHR rt_props{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_PROPERTIES_KHR};
    VkPhysicalDeviceAccelerationStructurePropertiesKHR as_props{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR};
    as_props.pNext = features_.ray_tracing_pipeline ? &rt_props : nullptr;
    VkPhysicalDeviceProperties2 rp2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    rp2.pNext = &as_props;
    vkGetPhysicalDeviceProperties2(physical_device_, &rp2);
    features_.scratch_offset_alignment = as_props.minAccelerationStructureScratchOffsetAlignment;
    if (features_.ray_tracing_pipeline) {
      features_.shader_group_handle_size = rt_props.shaderGroupHandleSize;
      features_.shader_group_handle_alignment = rt_props.shaderGroupHandleAlignment;
      features_.shader_group_base_alignment = rt_props.shaderGroupBaseAlignment;
    }
  }
  if (!features_.ray_tracing_pipeline) {
    const RayTracingSupport rt_device = device.ray_tracing();
    const std::string name = std::string("device ") + properties_.deviceName;
    features_.ray_tracing_missing =
        !rt_device.extensions ? name + " lacks " VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME
        : !rt_device.base     ? name + " lacks the accelerationStructure/bufferDeviceAddress features"
        : !rt_device.pipeline ? name + " lacks " VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME
                              : name + " has ray tracing but it was not enabled on the device (" +
                                    VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME + ", " +
                                    VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME + ", " +
                                    VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME +
                                    ", accelerationStructure, bufferDeviceAddress, rayTracingPipeline)";
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
  const VkShaderStageFlags needed_stages = VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  features_.subgroup_arithmetic_compute_fragment = (subgroup.supportedOperations & kSubgroupOps) == kSubgroupOps &&
                                                   (subgroup.supportedStages & needed_stages) == needed_stages &&
                                                   !masked("subgroup_arithmetic");
  driver_description_ = std::string(driver.driverName) + " " + driver.driverInfo;
  max_allocation_size_ = maintenance3.maxMemoryAllocationSize;
  features_.timestamps = queue_families(physical_device_)[queue_family_].timestampValidBits > 0;
  features_.timestamp_period_ns = properties_.limits.timestampPeriod;
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

  const VkDebugUtilsMessengerCreateInfoEXT messenger_info = messenger_create_info(this);

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
  VkResult r = vkCreateInstance(&info, allocator_, &instance_);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw VulkanError("no Vulkan 1.3 driver found (install mesa-vulkan-drivers for the CPU driver)");
  VK_CHECK(r);
  enabled_instance_extensions_.assign(extensions.begin(), extensions.end());

  load_instance_functions(vkGetInstanceProcAddr);
  if (validation_enabled_ && debug_utils_) create_messenger();
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
  const DeviceSupport support(physical_device_);
  auto require = [&](const char* name) {
    if (!support.has(name))
      throw VulkanError(std::string("device ") + properties_.deviceName + " lacks required extension " + name);
  };
  for (const auto& e : kDeviceExtensions) {
    if (e.required) require(e.name);
    if (support.wanted(e, masked_features_)) enabled_device_extensions_.emplace_back(e.name);
  }
  if (options.swapchain) {
    require(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
    enabled_device_extensions_.emplace_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  }
  // Required bits always, optional ones where the device has them; a masked feature is neither
  // enabled nor recorded, so using it anyway is a validation error.
  enabled_chain_ = std::make_unique<FeatureChain>();
  for (const auto& bit : kFeatureBits) {
    if (bit.required && !bit_of(support.features, bit))
      throw VulkanError(std::string("device ") + properties_.deviceName + " lacks required feature " + bit.name);
    *bit.field(*enabled_chain_) = support.wanted(bit, masked_features_) ? VK_TRUE : VK_FALSE;
  }
  enabled_chain_->link([&](const char* name) { return contains(enabled_device_extensions_, name); });

  const auto families = queue_families(physical_device_);
  const auto family = std::find_if(families.begin(), families.end(), graphics_and_compute);
  if (family == families.end())
    throw VulkanError(std::string("device ") + properties_.deviceName + " has no graphics+compute queue");
  queue_family_ = static_cast<uint32_t>(family - families.begin());
  detect_features(support, *enabled_chain_, enabled_device_extensions_);

  float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  queue_info.queueFamilyIndex = queue_family_;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;

  std::vector<const char*> extensions;
  for (const auto& e : enabled_device_extensions_) extensions.push_back(e.c_str());
  VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  info.pNext = &enabled_chain_->f2;
  info.queueCreateInfoCount = 1;
  info.pQueueCreateInfos = &queue_info;
  info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  VK_CHECK(vkCreateDevice(physical_device_, &info, allocator_, &device_));
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
  load_device_functions(vkGetDeviceProcAddr);
  create_command_pool();
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
  const VkResult r = vkAllocateMemory(device_, &info, allocator_, &memory);
  if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
    throw VulkanError(what + " needs " + std::to_string(info.allocationSize) + " bytes, and " +
                      properties_.deviceName + " is out of memory (" + vk_result_name(r) + ")");
  VK_CHECK(r);
  return memory;
}

void Context::free_memory(VkDeviceMemory memory) const {
  if (!memory) return;
  vkFreeMemory(device_, memory, allocator_);
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
  VK_CHECK(vkCreateFence(device_, &fence_info, allocator_, &fence));
  record_submit_wait(cmd, fence, record);
  vkDestroyFence(device_, fence, allocator_);
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
