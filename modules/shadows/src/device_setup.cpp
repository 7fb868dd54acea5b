// shadows::DeviceSetup: the module's device requirements turned into what vkCreateDevice takes.
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "shadows/context.hpp"

namespace shadows {

namespace {

// Every feature structure the module names or merges is VkBool32 members after sType and pNext, so
// merging two of a kind is ORing their words.
template <typename T>
void or_words(T& into, const void* from) {
  constexpr size_t first = offsetof(T, pNext) + sizeof(void*);
  constexpr size_t count = (sizeof(T) - first) / sizeof(VkBool32);
  auto* dst = reinterpret_cast<VkBool32*>(reinterpret_cast<char*>(&into) + first);
  const auto* src = reinterpret_cast<const VkBool32*>(static_cast<const char*>(from) + first);
  for (size_t i = 0; i < count; ++i) dst[i] = dst[i] || src[i] ? VK_TRUE : VK_FALSE;
}

template <typename T>
bool any_word(const void* s) {
  constexpr size_t first = offsetof(T, pNext) + sizeof(void*);
  const auto* words = reinterpret_cast<const VkBool32*>(static_cast<const char*>(s) + first);
  return std::any_of(words, words + (sizeof(T) - first) / sizeof(VkBool32), [](VkBool32 b) { return b != VK_FALSE; });
}

void set_if(VkBool32& bit, VkBool32 value) {
  if (value) bit = VK_TRUE;
}

}  // namespace

struct DeviceSetup::Impl {
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceFragmentShaderBarycentricFeaturesKHR bary{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FRAGMENT_SHADER_BARYCENTRIC_FEATURES_KHR};
  VkPhysicalDeviceAccelerationStructureFeaturesKHR as{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR};
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR rtp{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR};
  VkPhysicalDeviceRayQueryFeaturesKHR rq{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR};
  std::vector<std::string> extensions;
  std::vector<const char*> extension_names;
  std::vector<DeviceRequirement> optional;
  std::string missing;

  bool listed(const char* name) const { return std::find(extensions.begin(), extensions.end(), name) != extensions.end(); }

  // The member a feature name of device_requirements() stands for, or null.
  VkBool32* bit(const std::string& name) {
#define SHADOWS_FEATURE(s, member) \
  if (name == #member) return &s.member;
    SHADOWS_FEATURE(f2.features, geometryShader)
    SHADOWS_FEATURE(f2.features, fragmentStoresAndAtomics)
    SHADOWS_FEATURE(f2.features, vertexPipelineStoresAndAtomics)
    SHADOWS_FEATURE(f2.features, shaderInt64)
    SHADOWS_FEATURE(f2.features, shaderStorageImageWriteWithoutFormat)
    SHADOWS_FEATURE(f2.features, depthClamp)
    SHADOWS_FEATURE(f2.features, fillModeNonSolid)
    SHADOWS_FEATURE(f2.features, independentBlend)
    SHADOWS_FEATURE(f2.features, pipelineStatisticsQuery)
    SHADOWS_FEATURE(f12, scalarBlockLayout)
    SHADOWS_FEATURE(f12, hostQueryReset)
    SHADOWS_FEATURE(f12, shaderInt8)
    SHADOWS_FEATURE(f12, storageBuffer8BitAccess)
    SHADOWS_FEATURE(f12, bufferDeviceAddress)
    SHADOWS_FEATURE(f13, synchronization2)
    SHADOWS_FEATURE(f13, dynamicRendering)
    SHADOWS_FEATURE(f13, maintenance4)
    SHADOWS_FEATURE(bary, fragmentShaderBarycentric)
    SHADOWS_FEATURE(as, accelerationStructure)
    SHADOWS_FEATURE(rtp, rayTracingPipeline)
    SHADOWS_FEATURE(rq, rayQuery)
#undef SHADOWS_FEATURE
    return nullptr;
  }

  // The chain vkCreateDevice may take: core structures always, an extension's only when it is listed.
  void relink() {
    void** tail = &f2.pNext;
    auto append = [&](auto& s) {
      *tail = &s;
      tail = &s.pNext;
    };
    append(f11);
    append(f12);
    append(f13);
    if (listed(VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME)) append(bary);
    if (listed(VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME)) append(as);
    if (listed(VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME)) append(rtp);
    if (listed(VK_KHR_RAY_QUERY_EXTENSION_NAME)) append(rq);
    *tail = nullptr;
    extension_names.clear();
    for (const auto& e : extensions) extension_names.push_back(e.c_str());
  }

  // An extension structure of the host's: merged when its extension is listed, refused otherwise.
  template <typename T>
  void merge_extension_structure(T& into, const void* from, const char* extension, const char* structure) {
    if (!any_word<T>(from)) return;
    if (!listed(extension))
      throw Error(std::string("shadows: DeviceSetup::add_features: ") + structure + " sets bits but " + extension +
                  " is not in the extension list (add_extension first)");
    or_words(into, from);
  }
};

DeviceSetup::DeviceSetup(VkPhysicalDevice physical_device, const std::vector<std::string>& leave_out)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const DeviceRequirements req = device_requirements(physical_device);
  m.missing = req.missing;
  const auto left_out = [&](const std::string& name) {
    return std::find(leave_out.begin(), leave_out.end(), name) != leave_out.end();
  };
  for (const auto* list : {&req.required_extensions, &req.optional_extensions})
    for (const DeviceRequirement& e : *list) {
      if (left_out(e.name)) continue;
      m.extensions.push_back(e.name);
      if (list == &req.optional_extensions) m.optional.push_back(e);
    }
  for (const auto* list : {&req.required_features, &req.optional_features})
    for (const DeviceRequirement& f : *list) {
      if (left_out(f.name)) continue;
      VkBool32* bit = m.bit(f.name);
      if (!bit) {
        if (m.missing.empty()) m.missing = "shadows: DeviceSetup does not know the feature " + f.name;
        continue;
      }
      *bit = VK_TRUE;
      if (list == &req.optional_features) m.optional.push_back(f);
    }
  m.relink();
}

DeviceSetup::~DeviceSetup() = default;
DeviceSetup::DeviceSetup(DeviceSetup&&) noexcept = default;
DeviceSetup& DeviceSetup::operator=(DeviceSetup&&) noexcept = default;

const std::string& DeviceSetup::missing() const { return impl_->missing; }
const std::vector<DeviceRequirement>& DeviceSetup::optional_items() const { return impl_->optional; }

DeviceSetup& DeviceSetup::add_extension(const char* name) {
  if (!name || !*name) throw Error("shadows: DeviceSetup::add_extension: name is null or empty");
  if (!impl_->listed(name)) impl_->extensions.emplace_back(name);
  impl_->relink();
  return *this;
}

DeviceSetup& DeviceSetup::add_features(const VkPhysicalDeviceFeatures2& host_chain) {
  Impl& m = *impl_;
  if (host_chain.sType != VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2)
    throw Error("shadows: DeviceSetup::add_features: the chain's root is not a VkPhysicalDeviceFeatures2 (sType " +
                std::to_string(int(host_chain.sType)) + ")");
  // The core structure's features are VkBool32 words as well.
  const auto* core_from = reinterpret_cast<const VkBool32*>(&host_chain.features);
  auto* core_into = reinterpret_cast<VkBool32*>(&m.f2.features);
  for (size_t i = 0; i < sizeof(VkPhysicalDeviceFeatures) / sizeof(VkBool32); ++i) set_if(core_into[i], core_from[i]);
  for (auto* s = static_cast<const VkBaseInStructure*>(host_chain.pNext); s; s = s->pNext) {
    switch (s->sType) {
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES: or_words(m.f11, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES: or_words(m.f12, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES: or_words(m.f13, s); break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES:
        set_if(m.f13.synchronization2, reinterpret_cast<const VkPhysicalDeviceSynchronization2Features*>(s)->synchronization2);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES:
        set_if(m.f13.dynamicRendering, reinterpret_cast<const VkPhysicalDeviceDynamicRenderingFeatures*>(s)->dynamicRendering);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_4_FEATURES:
        set_if(m.f13.maintenance4, reinterpret_cast<const VkPhysicalDeviceMaintenance4Features*>(s)->maintenance4);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_BUFFER_DEVICE_ADDRESS_FEATURES: {
        const auto* b = reinterpret_cast<const VkPhysicalDeviceBufferDeviceAddressFeatures*>(s);
        set_if(m.f12.bufferDeviceAddress, b->bufferDeviceAddress);
        set_if(m.f12.bufferDeviceAddressCaptureReplay, b->bufferDeviceAddressCaptureReplay);
        set_if(m.f12.bufferDeviceAddressMultiDevice, b->bufferDeviceAddressMultiDevice);
        break;
      }
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SCALAR_BLOCK_LAYOUT_FEATURES:
        set_if(m.f12.scalarBlockLayout, reinterpret_cast<const VkPhysicalDeviceScalarBlockLayoutFeatures*>(s)->scalarBlockLayout);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_HOST_QUERY_RESET_FEATURES:
        set_if(m.f12.hostQueryReset, reinterpret_cast<const VkPhysicalDeviceHostQueryResetFeatures*>(s)->hostQueryReset);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_TIMELINE_SEMAPHORE_FEATURES:
        set_if(m.f12.timelineSemaphore, reinterpret_cast<const VkPhysicalDeviceTimelineSemaphoreFeatures*>(s)->timelineSemaphore);
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_8BIT_STORAGE_FEATURES: {
        const auto* b = reinterpret_cast<const VkPhysicalDevice8BitStorageFeatures*>(s);
        set_if(m.f12.storageBuffer8BitAccess, b->storageBuffer8BitAccess);
        set_if(m.f12.uniformAndStorageBuffer8BitAccess, b->uniformAndStorageBuffer8BitAccess);
        set_if(m.f12.storagePushConstant8, b->storagePushConstant8);
        break;
      }
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_FLOAT16_INT8_FEATURES: {
        const auto* b = reinterpret_cast<const VkPhysicalDeviceShaderFloat16Int8Features*>(s);
        set_if(m.f12.shaderFloat16, b->shaderFloat16);
        set_if(m.f12.shaderInt8, b->shaderInt8);
        break;
      }
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FRAGMENT_SHADER_BARYCENTRIC_FEATURES_KHR:
        m.merge_extension_structure(m.bary, s, VK_KHR_FRAGMENT_SHADER_BARYCENTRIC_EXTENSION_NAME,
                                    "VkPhysicalDeviceFragmentShaderBarycentricFeaturesKHR");
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR:
        m.merge_extension_structure(m.as, s, VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME,
                                    "VkPhysicalDeviceAccelerationStructureFeaturesKHR");
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR:
        m.merge_extension_structure(m.rtp, s, VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME,
                                    "VkPhysicalDeviceRayTracingPipelineFeaturesKHR");
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR:
        m.merge_extension_structure(m.rq, s, VK_KHR_RAY_QUERY_EXTENSION_NAME, "VkPhysicalDeviceRayQueryFeaturesKHR");
        break;
      default:
        throw Error("shadows: DeviceSetup::add_features: cannot merge the structure of sType " +
                    std::to_string(int(s->sType)) + " (chain it after features() yourself)");
    }
  }
  m.relink();
  return *this;
}

const VkPhysicalDeviceFeatures2* DeviceSetup::features() const { return &impl_->f2; }
const char* const* DeviceSetup::extension_names() const { return impl_->extension_names.data(); }
uint32_t DeviceSetup::extension_count() const { return uint32_t(impl_->extension_names.size()); }

void DeviceSetup::describe(ContextDesc& desc) const {
  desc.enabled_device_extension_names = impl_->extension_names.data();
  desc.enabled_device_extension_count = uint32_t(impl_->extension_names.size());
  desc.enabled_features = &impl_->f2;
}

}  // namespace shadows
