// A context adopting a device that a host created: here the device of an owning context, enabled
// exactly as that context enabled it, so both must report the same features and share one device.
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <mutex>
#include <new>
#include <unordered_map>

#include <shared/cascades.h>

#include "gpu/pipeline.hpp"
#include "gpu/resources.hpp"
#include "gpu_fixture.hpp"

namespace {

using engine::gpu::AdoptedDevice;
using engine::gpu::Context;
namespace gs = gpu_shared;

// Allocation callbacks that count: every object created with them must be freed with them, and the
// validation layer reports a create/destroy pair that disagrees.
class CountingAllocator {
 public:
  CountingAllocator() {
    callbacks_.pUserData = this;
    callbacks_.pfnAllocation = [](void* user, size_t size, size_t alignment, VkSystemAllocationScope) -> void* {
      return static_cast<CountingAllocator*>(user)->allocate(size, alignment);
    };
    callbacks_.pfnReallocation = [](void* user, void* old, size_t size, size_t alignment,
                                    VkSystemAllocationScope) -> void* {
      return static_cast<CountingAllocator*>(user)->reallocate(old, size, alignment);
    };
    callbacks_.pfnFree = [](void* user, void* memory) { static_cast<CountingAllocator*>(user)->release(memory); };
  }
  const VkAllocationCallbacks* callbacks() const { return &callbacks_; }
  size_t total() const { return total_; }
  size_t live() const {
    std::lock_guard lock(mutex_);
    return blocks_.size();
  }

 private:
  struct Block {
    size_t size;
    size_t alignment;
  };
  void* allocate(size_t size, size_t alignment) {
    if (size == 0) return nullptr;
    void* p = ::operator new(size, std::align_val_t(alignment), std::nothrow);
    if (!p) return nullptr;
    std::lock_guard lock(mutex_);
    blocks_[p] = {size, alignment};
    ++total_;
    return p;
  }
  void* reallocate(void* old, size_t size, size_t alignment) {
    if (!old) return allocate(size, alignment);
    if (size == 0) {
      release(old);
      return nullptr;
    }
    void* p = allocate(size, alignment);
    if (!p) return nullptr;
    size_t old_size = 0;
    {
      std::lock_guard lock(mutex_);
      old_size = blocks_.at(old).size;
    }
    std::memcpy(p, old, std::min(size, old_size));
    release(old);
    return p;
  }
  void release(void* p) {
    if (!p) return;
    size_t alignment = 0;
    {
      std::lock_guard lock(mutex_);
      auto it = blocks_.find(p);
      ASSERT_NE(it, blocks_.end()) << "freed a block the allocator did not hand out";
      alignment = it->second.alignment;
      blocks_.erase(it);
    }
    ::operator delete(p, std::align_val_t(alignment));
  }

  VkAllocationCallbacks callbacks_{};
  mutable std::mutex mutex_;
  std::unordered_map<void*, Block> blocks_;
  std::atomic<size_t> total_{0};
};

// What a host hands over: the owning context's handles and exactly what it enabled.
AdoptedDevice adoption_of(const Context& owner) {
  AdoptedDevice host;
  host.instance = owner.instance();
  host.physical_device = owner.physical_device();
  host.device = owner.device();
  host.queue_family = owner.queue_family();
  host.queue = owner.queue();
  host.get_instance_proc_addr = vkGetInstanceProcAddr;
  host.get_device_proc_addr = vkGetDeviceProcAddr;
  host.enabled_instance_extensions = owner.enabled_instance_extensions();
  host.enabled_device_extensions = owner.enabled_device_extensions();
  host.enabled_features = owner.enabled_features();
  host.api_version = owner.api_version();
  host.count_validation_messages = true;
  return host;
}

// The message of the VulkanError that adopting `host` throws (empty when it does not throw).
std::string adoption_error(const AdoptedDevice& host) {
  try {
    Context adopted(host);
  } catch (const engine::gpu::VulkanError& e) {
    return e.what();
  }
  return {};
}

// Runs cascade_dispatch_args.comp on `ctx`: 100 kernel pixels make 2 groups of CASCADE_LIST_GROUP.
uint32_t kernel_groups(const Context& ctx) {
  engine::gpu::Buffer counters(ctx, gs::CASCADE_COUNTER_WORDS * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                               true, "adopted test counters");
  std::memset(counters.mapped(), 0, counters.size());
  counters.as<uint32_t>()[gs::CASCADE_COUNTER_KERNEL] = 100;
  engine::gpu::PipelineFactory factory(ctx);
  const engine::gpu::Pipeline pipeline = factory.compute(
      {"cascade_dispatch_args.comp", {{gs::CASCADE_ARGS_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}}, 0});
  ctx.immediate_submit([&](VkCommandBuffer cmd) {
    pipeline.bind(cmd);
    engine::gpu::DescriptorWriter().storage_buffer(gs::CASCADE_ARGS_BINDING_COUNTERS, counters.handle()).push(ctx, cmd, pipeline);
    vkCmdDispatch(cmd, 1, 1, 1);
    VkMemoryBarrier2 to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
    to_host.srcStageMask = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
    to_host.srcAccessMask = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
    to_host.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT;
    to_host.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT;
    VkDependencyInfo dependency{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dependency.memoryBarrierCount = 1;
    dependency.pMemoryBarriers = &to_host;
    vkCmdPipelineBarrier2(cmd, &dependency);
  });
  return counters.as<uint32_t>()[gs::CASCADE_COUNTER_DISPATCH_KERNEL];
}

class AdoptedDeviceTest : public GpuTest {};

TEST_F(AdoptedDeviceTest, RunsOnTheHostDeviceAndLeavesItAlive) {
  CountingAllocator counting;
  VkPipelineCacheCreateInfo cache_info{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
  VkPipelineCache cache = VK_NULL_HANDLE;
  ASSERT_EQ(vkCreatePipelineCache(ctx_->device(), &cache_info, nullptr, &cache), VK_SUCCESS);
  AdoptedDevice host = adoption_of(*ctx_);
  host.allocator = counting.callbacks();
  host.pipeline_cache = cache;
  {
    Context adopted(host);
    EXPECT_TRUE(ctx_->owns_device());
    EXPECT_FALSE(adopted.owns_device());
    EXPECT_EQ(adopted.device(), ctx_->device());
    EXPECT_EQ(adopted.queue(), ctx_->queue());
    EXPECT_EQ(adopted.allocator(), counting.callbacks());
    EXPECT_EQ(adopted.pipeline_cache(), cache);
    EXPECT_NE(adopted.command_pool(), ctx_->command_pool());
    EXPECT_TRUE(adopted.validation_enabled()) << "the host enabled VK_EXT_debug_utils: messages are counted";
    EXPECT_TRUE(adopted.features() == ctx_->features()) << "the same device, enabled the same way";
    EXPECT_EQ(adopted.features().ray_tracing_missing, ctx_->features().ray_tracing_missing);
    EXPECT_EQ(adopted.driver_description(), ctx_->driver_description());
    EXPECT_EQ(adopted.max_memory_allocation_size(), ctx_->max_memory_allocation_size());
    EXPECT_EQ(adopted.enabled_device_extensions(), ctx_->enabled_device_extensions());

    engine::gpu::Image image(adopted, {16, 16}, VK_FORMAT_R8G8B8A8_UNORM,
                             VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, "adopted test image");
    EXPECT_NE(image.handle(), VK_NULL_HANDLE);
    EXPECT_EQ(kernel_groups(adopted), 2u);
    EXPECT_GT(counting.total(), 0u) << "the host's allocation callbacks were not used";
    EXPECT_EQ(adopted.validation_message_count(), 0u);
  }
  EXPECT_EQ(counting.live(), 0u) << "an object created with the host's callbacks outlived the context";
  // The host's device, queue and instance are untouched: the owner still runs work.
  EXPECT_EQ(kernel_groups(*ctx_), 2u);
  vkDestroyPipelineCache(ctx_->device(), cache, nullptr);
}

// A feature the device has but the host did not enable is absent; so is a masked one.
TEST_F(AdoptedDeviceTest, FeaturesAreWhatTheHostEnabled) {
  const auto& owner = ctx_->features();
  // Only the required bits, given as the single-feature structures Vulkan 1.3 promoted.
  VkPhysicalDeviceDynamicRenderingFeatures dynamic_rendering{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  dynamic_rendering.dynamicRendering = VK_TRUE;
  VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES};
  sync2.synchronization2 = VK_TRUE;
  sync2.pNext = &dynamic_rendering;
  VkPhysicalDeviceFeatures2 minimal{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  minimal.pNext = &sync2;
  AdoptedDevice host = adoption_of(*ctx_);
  host.enabled_features = &minimal;
  host.enabled_device_extensions = {VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME};
  host.masked_features = {"subgroup_arithmetic"};
  {
    Context adopted(host);
    const auto& f = adopted.features();
    EXPECT_FALSE(f.geometry_shader);
    EXPECT_FALSE(f.depth_clamp);
    EXPECT_FALSE(f.shader_int64);
    EXPECT_FALSE(f.fragment_stores_and_atomics);
    EXPECT_FALSE(f.conservative_rasterization);
    EXPECT_FALSE(f.fragment_shader_barycentric);
    EXPECT_FALSE(f.acceleration_structure);
    EXPECT_FALSE(f.ray_tracing_pipeline);
    EXPECT_FALSE(f.buffer_device_address);
    EXPECT_FALSE(f.subgroup_arithmetic_compute_fragment);
    EXPECT_FALSE(f.ray_tracing_missing.empty());
    EXPECT_EQ(f.max_storage_buffer_range, owner.max_storage_buffer_range);
    EXPECT_EQ(f.subgroup_size, owner.subgroup_size);
    EXPECT_EQ(f.timestamps, owner.timestamps);
    EXPECT_TRUE(adopted.enabled_features()->pNext != nullptr);
    EXPECT_EQ(kernel_groups(adopted), 2u);
  }
  // The owner's enabled features bring the owner's paths back, one by one.
  host = adoption_of(*ctx_);
  host.enabled_device_extensions.erase(
      std::remove(host.enabled_device_extensions.begin(), host.enabled_device_extensions.end(),
                  std::string(VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME)),
      host.enabled_device_extensions.end());
  Context without_conservative(host);
  EXPECT_FALSE(without_conservative.features().conservative_rasterization);
  EXPECT_EQ(without_conservative.features().geometry_shader, owner.geometry_shader);
}

TEST_F(AdoptedDeviceTest, BadFieldsAreRefusedInOneLine) {
  const AdoptedDevice good = adoption_of(*ctx_);
  struct Case {
    const char* expected;  // the text the error must hold
    std::function<void(AdoptedDevice&)> spoil;
  };
  const Case cases[] = {
      {"AdoptedDevice.instance is VK_NULL_HANDLE", [](AdoptedDevice& h) { h.instance = VK_NULL_HANDLE; }},
      {"AdoptedDevice.physical_device is VK_NULL_HANDLE", [](AdoptedDevice& h) { h.physical_device = VK_NULL_HANDLE; }},
      {"AdoptedDevice.device is VK_NULL_HANDLE", [](AdoptedDevice& h) { h.device = VK_NULL_HANDLE; }},
      {"AdoptedDevice.queue is VK_NULL_HANDLE", [](AdoptedDevice& h) { h.queue = VK_NULL_HANDLE; }},
      {"AdoptedDevice.get_instance_proc_addr is null", [](AdoptedDevice& h) { h.get_instance_proc_addr = nullptr; }},
      {"AdoptedDevice.get_device_proc_addr is null", [](AdoptedDevice& h) { h.get_device_proc_addr = nullptr; }},
      {"AdoptedDevice.api_version is 1.2", [](AdoptedDevice& h) { h.api_version = VK_API_VERSION_1_2; }},
      {"AdoptedDevice.queue_family 99", [](AdoptedDevice& h) { h.queue_family = 99; }},
      {"AdoptedDevice.enabled_device_extensions lacks VK_KHR_push_descriptor",
       [](AdoptedDevice& h) { h.enabled_device_extensions.clear(); }},
      {"AdoptedDevice.enabled_features lacks synchronization2", [](AdoptedDevice& h) { h.enabled_features = nullptr; }},
  };
  for (const auto& c : cases) {
    AdoptedDevice host = good;
    c.spoil(host);
    const std::string error = adoption_error(host);
    EXPECT_EQ(error.rfind("shadows: ", 0), 0u) << error;
    EXPECT_NE(error.find(c.expected), std::string::npos) << "expected '" << c.expected << "', got '" << error << "'";
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  // dynamicRendering off in an otherwise complete chain.
  VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES};
  sync2.synchronization2 = VK_TRUE;
  VkPhysicalDeviceFeatures2 partial{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  partial.pNext = &sync2;
  AdoptedDevice host = good;
  host.enabled_features = &partial;
  EXPECT_EQ(adoption_error(host), "shadows: AdoptedDevice.enabled_features lacks dynamicRendering");
}

// device_requirements() and the owning context read one table: what the owner enabled is what a host
// is told to enable on the same physical device.
TEST_F(AdoptedDeviceTest, RequirementsMatchWhatTheOwnerEnables) {
  const auto req = engine::gpu::device_requirements(ctx_->physical_device());
  auto has = [](const std::vector<std::string>& list, const std::string& name) {
    return std::find(list.begin(), list.end(), name) != list.end();
  };
  EXPECT_TRUE(has(req.required_device_extensions, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME));
  EXPECT_TRUE(has(req.required_features, "synchronization2"));
  EXPECT_TRUE(has(req.required_features, "dynamicRendering"));
  EXPECT_FALSE(has(req.required_features, "timelineSemaphore"));
  EXPECT_EQ(has(req.optional_features, "geometryShader"), ctx_->features().geometry_shader ||
                                                               has(ctx_->masked_features(), "geometry_shader"));
  EXPECT_EQ(has(req.optional_device_extensions, VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME),
            ctx_->features().conservative_rasterization || has(ctx_->masked_features(), "conservative_rasterization"));
  EXPECT_EQ(has(req.optional_features, "rayTracingPipeline"), ctx_->features().ray_tracing_pipeline);
  if (ctx_->masked_features().empty()) {
    std::vector<std::string> listed = req.required_device_extensions;
    listed.insert(listed.end(), req.optional_device_extensions.begin(), req.optional_device_extensions.end());
    EXPECT_EQ(listed, ctx_->enabled_device_extensions());
  }
}

}  // namespace
