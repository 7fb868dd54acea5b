#pragma once
// The Vulkan instance, the chosen physical device, one universal queue, and the record of which
// optional features the device offers. Every other part of the engine asks `features()` rather than
// querying Vulkan itself. A Context either creates its own instance and device (ContextOptions) or
// adopts a device that a host application created (AdoptedDevice).
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <vulkan/vulkan.h>

#include "gpu/vk_check.hpp"

namespace engine::gpu {

struct DeviceFeatures {
  bool conservative_rasterization = false;       // VK_EXT_conservative_rasterization
  bool conservative_underestimation = false;     // primitiveUnderestimation
  bool fully_covered_fragment_input = false;     // gl_FragFullyCoveredNV available
  float conservative_overestimation_size = 0.0f; // extraPrimitiveOverestimationSize ceiling in px
  bool fragment_shader_barycentric = false;      // VK_KHR_fragment_shader_barycentric
  bool geometry_shader = false;
  bool depth_clamp = false;
  bool timestamps = false;                       // timestampComputeAndGraphics on the queue
  float timestamp_period_ns = 1.0f;
  // Ray tracing: VK_KHR_acceleration_structure (+ deferred_host_operations, bufferDeviceAddress) with
  // VK_KHR_ray_tracing_pipeline and/or VK_KHR_ray_query, all enabled together when present.
  bool acceleration_structure = false;
  bool ray_tracing_pipeline = false;
  bool ray_query = false;
  bool buffer_device_address = false;
  // Empty when the ray-traced technique can run; else one line naming what the device lacks.
  std::string ray_tracing_missing;
  uint32_t shader_group_handle_size = 0;
  uint32_t shader_group_handle_alignment = 0;
  uint32_t shader_group_base_alignment = 0;
  uint32_t scratch_offset_alignment = 0;         // minAccelerationStructureScratchOffsetAlignment
  uint64_t max_storage_buffer_range = 0;         // limits.maxStorageBufferRange (bytes)
  bool shader_int64 = false;
  bool fragment_stores_and_atomics = false;
  bool vertex_stores_and_atomics = false;
  uint32_t subgroup_size = 0;
  // Subgroup basic, arithmetic and ballot operations in compute and fragment shaders (the shadow
  // passes reduce their counters per subgroup and reserve list slots a subgroup at a time).
  // A shader declaring a SPIR-V capability whose feature is absent here (geometry shaders, 64-bit
  // integers, these subgroup operations, ray tracing pipelines, fragment shader barycentrics) is
  // refused in one line when its module is made (ShaderModule).
  bool subgroup_arithmetic_compute_fragment = false;

  bool operator==(const DeviceFeatures&) const = default;
};

struct ContextOptions {
  // "gpu" (first discrete/integrated GPU), "lavapipe" (Mesa's CPU driver), a device index, or empty
  // for automatic: a GPU if there is one, else lavapipe.
  std::string device;
  // Khronos validation + debug messenger. Also forced on by ENGINE_VALIDATION=1, and on in debug builds.
  bool validation = false;
  std::vector<const char*> instance_extensions;  // e.g. from the window system
  bool swapchain = false;                        // enable VK_KHR_swapchain on the device
  std::string application_name = "shadow_engine";
  // Optional features to treat as absent, as on a device without them (tests of the other paths):
  // "conservative_rasterization", "geometry_shader", "fragment_shader_barycentric",
  // "subgroup_arithmetic" (subgroup arithmetic and ballot operations). ENGINE_MASK_FEATURES
  // (comma-separated) adds to the list.
  std::vector<std::string> masked_features;
  // The validation layer's synchronization checks (hazards between commands); needs validation.
  // Also forced on by ENGINE_SYNC_VALIDATION=1 (which turns validation on too).
  bool sync_validation = false;
};

// The names ContextOptions::masked_features accepts.
const std::vector<std::string>& maskable_feature_names();

// A device created by a host application, for the engine to run on. The host keeps ownership: the
// context never destroys the instance, the device or the queue. Every handle must stay valid for the
// context's lifetime; the lists and the features chain are read only during construction.
struct AdoptedDevice {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  // A family with graphics and compute; `queue` is a queue of it. The engine submits on `queue` from
  // the thread that calls into it, so the host must not use that queue concurrently (Vulkan's
  // external synchronization rule for queues).
  uint32_t queue_family = 0;
  VkQueue queue = VK_NULL_HANDLE;
  PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;  // required
  PFN_vkGetDeviceProcAddr get_device_proc_addr = nullptr;      // required
  // What the host enabled when it created the instance and the device: the context uses exactly these
  // (a feature the physical device has but the host did not enable counts as absent).
  std::vector<std::string> enabled_instance_extensions;
  std::vector<std::string> enabled_device_extensions;
  // The pNext chain given to vkCreateDevice (may be null: core features none). Its root must be a
  // VkPhysicalDeviceFeatures2 (a host that used pEnabledFeatures wraps them in one). Recognized in the
  // chain: VkPhysicalDeviceVulkan11/12/13Features, the promoted single-feature structures
  // (synchronization2, dynamic rendering, maintenance4, buffer device address, scalar block layout,
  // host query reset, float16/int8, 8-bit storage), fragment shader barycentric, acceleration
  // structure, ray tracing pipeline and ray query; other structures are skipped.
  const VkPhysicalDeviceFeatures2* enabled_features = nullptr;
  uint32_t api_version = VK_API_VERSION_1_3;  // the instance's apiVersion; at least 1.3
  const VkAllocationCallbacks* allocator = nullptr;  // used for every object the context and resources create
  VkPipelineCache pipeline_cache = VK_NULL_HANDLE;   // used for every pipeline created
  // Count validation messages through a debug messenger created on the host's instance (only when the
  // host enabled VK_EXT_debug_utils on it); tests turn this on.
  bool count_validation_messages = false;
  std::vector<std::string> masked_features;  // as ContextOptions::masked_features
};

// What a host enables on its device for the engine to run on it (AdoptedDevice), for one physical
// device. The owning Context enables from the same table, so the two never disagree.
struct DeviceRequirements {
  std::vector<std::string> required_device_extensions;  // must be enabled (VK_KHR_push_descriptor)
  // Enable when present: each unlocks a faster or extra path (conservative rasterization, fragment
  // shader barycentric, acceleration structure + deferred host operations + ray tracing pipeline /
  // ray query). Lists only what this physical device supports.
  std::vector<std::string> optional_device_extensions;
  // Feature bits by their Vulkan member name ("synchronization2", "dynamicRendering", "geometryShader",
  // "fragmentStoresAndAtomics", "shaderInt64", "bufferDeviceAddress", ...), in
  // VkPhysicalDeviceFeatures, VkPhysicalDeviceVulkan12/13Features or the extension's features
  // structure. The optional list holds only bits this physical device supports.
  std::vector<std::string> required_features, optional_features;
};
DeviceRequirements device_requirements(VkPhysicalDevice physical_device);

struct FeatureChain;   // the feature structures a context reads and enables (context.cpp)
struct DeviceSupport;  // what a physical device offers (context.cpp)

class Context {
 public:
  // Creates an instance and a device of its own, enabling every optional feature the device has.
  explicit Context(const ContextOptions& options);
  // Runs on the host's device. Throws VulkanError (a std::runtime_error) with one line naming the bad
  // field or what the device lacks: a null handle or entry point, an api_version under 1.3, a queue
  // family without graphics and compute, VK_KHR_push_descriptor not enabled, synchronization2 or
  // dynamicRendering not enabled. Creates only a command pool on `queue_family` (and a debug
  // messenger when asked); features() is what the device has AND the host enabled, less
  // masked_features.
  explicit Context(const AdoptedDevice& host);
  // Waits for the device to be idle, then destroys what the context created: its command pool and
  // messenger, and when it owns them, the device and the instance. Objects made from the context
  // (Buffer, Image, Pipeline, ...) must be destroyed first.
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_device_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  VkCommandPool command_pool() const { return command_pool_; }
  const DeviceFeatures& features() const { return features_; }
  const VkPhysicalDeviceProperties& properties() const { return properties_; }
  std::string device_name() const { return properties_.deviceName; }
  std::string driver_description() const { return driver_description_; }
  // Owning: the validation layer is on. Adopted: validation messages are counted (the messenger).
  bool validation_enabled() const { return validation_enabled_; }

  // False for an adopted device: the destructor then leaves the host's device and instance alone.
  bool owns_device() const { return owns_device_; }
  // Passed to every vkCreate*/vkDestroy*/vkAllocateMemory/vkFreeMemory of the context and the
  // resources made from it (null for an owning context).
  const VkAllocationCallbacks* allocator() const { return allocator_; }
  // Passed to every vkCreate*Pipelines (VK_NULL_HANDLE for an owning context).
  VkPipelineCache pipeline_cache() const { return pipeline_cache_; }
  // What the device was created with: for an owning context exactly what it gave vkCreateDevice /
  // vkCreateInstance; for an adopted one the host's lists and the feature bits the engine reads,
  // each set only where the device has it and the host enabled it. Enough to adopt the same device.
  const std::vector<std::string>& enabled_instance_extensions() const { return enabled_instance_extensions_; }
  const std::vector<std::string>& enabled_device_extensions() const { return enabled_device_extensions_; }
  const VkPhysicalDeviceFeatures2* enabled_features() const;
  uint32_t api_version() const { return api_version_; }

  // Count of validation/debug messages of warning or error severity since creation (or the last reset).
  uint32_t validation_message_count() const { return validation_messages_.load(); }
  void reset_validation_message_count() { validation_messages_ = 0; }
  std::vector<std::string> validation_messages() const;

  // Live device memory allocations of Buffer and Image, by debug name: a pass's memory is the sum
  // over the names it gives its resources (the shadow module reports it per technique).
  struct Allocation {
    std::string name;
    VkDeviceSize bytes = 0;
  };
  void track_allocation(VkDeviceMemory memory, const std::string& name, VkDeviceSize bytes) const;
  void untrack_allocation(VkDeviceMemory memory) const;
  std::vector<Allocation> allocations() const;

  uint32_t find_memory_type(uint32_t type_bits, VkMemoryPropertyFlags properties) const;
  bool sync_validation_enabled() const { return sync_validation_enabled_; }
  const std::vector<std::string>& masked_features() const { return masked_features_; }

  // Buffer and Image allocate through these: the allocation is checked against the device's largest
  // single allocation first, and running out of memory is one line naming `what`, not a driver failure.
  VkDeviceMemory allocate_memory(const VkMemoryAllocateInfo& info, const std::string& what) const;
  void free_memory(VkDeviceMemory memory) const;
  uint32_t live_allocation_count() const;  // Buffer and Image memory now allocated (allocations())
  VkDeviceSize max_memory_allocation_size() const { return max_allocation_size_; }

  // Frames in flight. A context whose commands go into frames that may still run on the GPU (a
  // module recording into a host's frames) turns deferral on: Buffer, Image and Sampler objects
  // released then are destroyed only once release_through() reports the frame they were released in
  // as completed. Off (the default), they are destroyed at once, as the engine waits for its frames.
  void defer_releases(bool on) { defer_releases_ = on; }
  bool defers_releases() const { return defer_releases_; }
  void set_recording_frame(uint64_t frame) { recording_frame_ = frame; }
  void defer_release(std::function<void()> destroy) const;
  void release_through(uint64_t completed_frame) const;
  void release_all_deferred() const;

  // Records commands into a fresh command buffer, submits it and waits. For uploads, readbacks, tests.
  void immediate_submit(const std::function<void(VkCommandBuffer)>& record) const;
  // Records into an existing command buffer (reset first), submits it with `fence` (reset first) and
  // waits for the fence.
  void record_submit_wait(VkCommandBuffer cmd, VkFence fence,
                          const std::function<void(VkCommandBuffer)>& record) const;

  // VK_EXT_debug_utils names (no-ops when the extension is absent).
  void set_name(VkObjectType type, uint64_t handle, const std::string& name) const;
  template <typename T>
  void set_name(T handle, VkObjectType type, const std::string& name) const {
    set_name(type, reinterpret_cast<uint64_t>(handle), name);
  }
  void begin_label(VkCommandBuffer cmd, const char* name) const;
  void end_label(VkCommandBuffer cmd) const;

  // Extension entry points fetched at device creation.
  PFN_vkCmdPushDescriptorSetKHR cmd_push_descriptor_set = nullptr;
  // Ray tracing entry points (null unless features().acceleration_structure / ray_tracing_pipeline).
  struct RayTracingFunctions {
    PFN_vkCreateAccelerationStructureKHR create_acceleration_structure = nullptr;
    PFN_vkDestroyAccelerationStructureKHR destroy_acceleration_structure = nullptr;
    PFN_vkGetAccelerationStructureBuildSizesKHR get_build_sizes = nullptr;
    PFN_vkGetAccelerationStructureDeviceAddressKHR get_acceleration_structure_address = nullptr;
    PFN_vkCmdBuildAccelerationStructuresKHR cmd_build_acceleration_structures = nullptr;
    PFN_vkCreateRayTracingPipelinesKHR create_ray_tracing_pipelines = nullptr;
    PFN_vkGetRayTracingShaderGroupHandlesKHR get_shader_group_handles = nullptr;
    PFN_vkCmdTraceRaysKHR cmd_trace_rays = nullptr;
  } rt;

 private:
  void create_instance(const ContextOptions& options);
  void pick_physical_device(const ContextOptions& options);
  void create_device(const ContextOptions& options);
  // Shared by both constructors.
  void set_masked_features(const std::vector<std::string>& masked);
  void detect_features(const DeviceSupport& device, const FeatureChain& enabled,
                       const std::vector<std::string>& device_extensions);
  void load_instance_functions(PFN_vkGetInstanceProcAddr get_instance_proc_addr);
  void create_messenger();
  void load_device_functions(PFN_vkGetDeviceProcAddr get_device_proc_addr);
  void create_command_pool();

  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  VkCommandPool command_pool_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_properties_{};
  DeviceFeatures features_;
  std::string driver_description_;
  bool validation_enabled_ = false;
  bool sync_validation_enabled_ = false;
  std::vector<std::string> masked_features_;
  VkDeviceSize max_allocation_size_ = 0;
  bool debug_utils_ = false;
  bool defer_releases_ = false;
  uint64_t recording_frame_ = 0;
  struct Deferred {
    uint64_t frame;
    std::function<void()> destroy;
  };
  mutable std::vector<Deferred> deferred_;
  bool owns_device_ = true;
  const VkAllocationCallbacks* allocator_ = nullptr;
  VkPipelineCache pipeline_cache_ = VK_NULL_HANDLE;
  uint32_t api_version_ = VK_API_VERSION_1_3;
  PFN_vkGetInstanceProcAddr get_instance_proc_addr_ = nullptr;
  std::vector<std::string> enabled_instance_extensions_;
  std::vector<std::string> enabled_device_extensions_;
  std::unique_ptr<FeatureChain> enabled_chain_;
  std::atomic<uint32_t> validation_messages_{0};
  mutable std::vector<std::string> message_log_;
  mutable std::unordered_map<VkDeviceMemory, Allocation> allocations_;
  PFN_vkSetDebugUtilsObjectNameEXT set_object_name_ = nullptr;
  PFN_vkCmdBeginDebugUtilsLabelEXT cmd_begin_label_ = nullptr;
  PFN_vkCmdEndDebugUtilsLabelEXT cmd_end_label_ = nullptr;

  friend VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                       VkDebugUtilsMessageTypeFlagsEXT,
                                                       const VkDebugUtilsMessengerCallbackDataEXT*, void*);
};

// RAII command-buffer region label.
class ScopedLabel {
 public:
  ScopedLabel(const Context& ctx, VkCommandBuffer cmd, const char* name) : ctx_(ctx), cmd_(cmd) {
    ctx_.begin_label(cmd_, name);
  }
  ~ScopedLabel() { ctx_.end_label(cmd_); }
  ScopedLabel(const ScopedLabel&) = delete;
  ScopedLabel& operator=(const ScopedLabel&) = delete;

 private:
  const Context& ctx_;
  VkCommandBuffer cmd_;
};

}  // namespace engine::gpu
