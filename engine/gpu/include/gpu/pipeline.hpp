#pragma once
// Shader modules, pipeline layouts with one push-descriptor set, compute and graphics pipelines, and a
// writer that pushes descriptors at record time (no pools, no set lifetime to manage).
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>
#include <memory>

#include "gpu/context.hpp"
#include "gpu/resources.hpp"

namespace engine::gpu {

// Where compiled SPIR-V lives: $ENGINE_SHADER_DIR if set, else "shaders/" next to the executable.
std::filesystem::path shader_directory();

// SPIR-V compiled into a library, so that a program linking it needs no shader folder. A library
// registers its table before creating pipelines (an explicit call: a static registration object in a
// static library would be dropped by the linker); ShaderModule looks here first, then on disk.
struct EmbeddedShader {
  const char* name;  // source file name, e.g. "izb_trace.comp"
  std::span<const uint32_t> code;
};
// Idempotent; the table must outlive every ShaderModule (a static array).
void register_embedded_shaders(std::span<const EmbeddedShader> shaders);
// The embedded SPIR-V named `name`, or an empty span.
std::span<const uint32_t> embedded_shader(const std::string& name);

class ShaderModule {
 public:
  // `name` is the source file name, e.g. "gbuffer.vert": the embedded SPIR-V of that name if a library
  // registered one, else <shader_directory>/<name>.spv. Throws VulkanError (one line) where the shader
  // declares a capability whose optional feature the device lacks or has masked (DeviceFeatures).
  ShaderModule(const Context& ctx, const std::string& name);
  ~ShaderModule();
  ShaderModule(const ShaderModule&) = delete;
  ShaderModule& operator=(const ShaderModule&) = delete;
  VkShaderModule handle() const { return module_; }

 private:
  const Context& ctx_;
  VkShaderModule module_ = VK_NULL_HANDLE;
};

struct Binding {
  uint32_t binding;
  VkDescriptorType type;
  VkShaderStageFlags stages = VK_SHADER_STAGE_ALL;
};

struct SpecializationConstant {
  uint32_t id;
  uint32_t value;
};

class Pipeline {
 public:
  Pipeline() = default;
  ~Pipeline() { reset(); }
  Pipeline(Pipeline&& o) noexcept { *this = std::move(o); }
  Pipeline& operator=(Pipeline&& o) noexcept;
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;
  void reset();

  VkPipeline handle() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }
  VkPipelineBindPoint bind_point() const { return bind_point_; }
  bool valid() const { return pipeline_ != VK_NULL_HANDLE; }
  void bind(VkCommandBuffer cmd) const { vkCmdBindPipeline(cmd, bind_point_, pipeline_); }
  template <typename T>
  void push_constants(VkCommandBuffer cmd, const T& value) const {
    vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_ALL, 0, sizeof(T), &value);
  }

 private:
  friend class PipelineFactory;
  const Context* ctx_ = nullptr;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineBindPoint bind_point_ = VK_PIPELINE_BIND_POINT_COMPUTE;
};

struct ComputePipelineDesc {
  std::string shader;  // e.g. "shading_points.comp"
  std::vector<Binding> bindings;
  uint32_t push_constant_size = 0;
  std::vector<SpecializationConstant> specialization;
};

// StandardVertex: one binding of kStandardVertexStride bytes, float3 position at 0, float3 normal at
// 12, float2 uv at 24 (the engine's and the shadow module's vertex buffers); PositionOnly: its
// position alone.
enum class VertexInput { None, StandardVertex, PositionOnly };
inline constexpr uint32_t kStandardVertexStride = 32;

enum class ConservativeMode { Off, Overestimate, Underestimate };

struct GraphicsPipelineDesc {
  std::string vertex_shader;
  std::string fragment_shader;  // empty: depth-only
  std::string geometry_shader;  // optional
  std::vector<Binding> bindings;
  uint32_t push_constant_size = 0;
  std::vector<SpecializationConstant> specialization;
  VertexInput vertex_input = VertexInput::StandardVertex;
  VkPrimitiveTopology topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  std::vector<VkFormat> color_formats;
  VkFormat depth_format = VK_FORMAT_UNDEFINED;
  bool depth_test = true;
  bool depth_write = true;
  VkCompareOp depth_compare = VK_COMPARE_OP_GREATER_OR_EQUAL;  // reversed Z by default
  VkCullModeFlags cull_mode = VK_CULL_MODE_BACK_BIT;
  VkFrontFace front_face = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  bool depth_clamp = false;
  bool depth_bias = false;  // when set, the bias values are dynamic state (vkCmdSetDepthBias)
  bool dynamic_depth_compare = false;  // vkCmdSetDepthCompareOp
  float depth_bias_constant = 0.0f;
  float depth_bias_slope = 0.0f;
  ConservativeMode conservative = ConservativeMode::Off;
  float conservative_extra_size = 0.0f;
  bool alpha_blend = false;
  bool color_write = true;
  std::string name;
};

// A ray tracing pipeline of one ray generation shader, miss shaders and triangle hit groups (each
// with optional closest-hit and any-hit shaders; a group with neither only records the hit). Shader
// groups are numbered raygen, misses, hit groups, which is the order ShaderBindingTable lays out.
struct RayTracingPipelineDesc {
  std::string raygen_shader;
  std::vector<std::string> miss_shaders;
  struct HitGroup {
    std::string closest_hit;  // empty: none
    std::string any_hit;      // empty: none
  };
  std::vector<HitGroup> hit_groups;
  std::vector<Binding> bindings;
  uint32_t push_constant_size = 0;
  std::vector<SpecializationConstant> specialization;
  uint32_t max_recursion_depth = 1;
  std::string name;
};

class PipelineFactory {
 public:
  explicit PipelineFactory(const Context& ctx) : ctx_(ctx) {}
  Pipeline compute(const ComputePipelineDesc& desc) const;
  Pipeline graphics(const GraphicsPipelineDesc& desc) const;
  // Needs features().ray_tracing_pipeline.
  Pipeline ray_tracing(const RayTracingPipelineDesc& desc) const;

 private:
  void make_layout(Pipeline& p, const std::vector<Binding>& bindings, uint32_t push_size) const;
  const Context& ctx_;
};

// The shader binding table of a ray tracing pipeline: one record per shader group (no shader record
// data), each region starting at shaderGroupBaseAlignment and each record padded to
// shaderGroupHandleAlignment, in a host-visible buffer read through its device address.
class ShaderBindingTable {
 public:
  ShaderBindingTable() = default;
  ShaderBindingTable(const Context& ctx, const Pipeline& pipeline, uint32_t miss_count, uint32_t hit_count,
                     const std::string& name);
  void trace(const Context& ctx, VkCommandBuffer cmd, uint32_t width, uint32_t height) const;
  VkDeviceSize size() const { return buffer_.size(); }

 private:
  Buffer buffer_;
  VkStridedDeviceAddressRegionKHR raygen_{}, miss_{}, hit_{}, callable_{};
};

// Collects descriptor writes for binding set 0 of a pipeline and pushes them in one call.
class DescriptorWriter {
 public:
  DescriptorWriter& storage_buffer(uint32_t binding, VkBuffer buffer, VkDeviceSize offset = 0,
                                   VkDeviceSize range = VK_WHOLE_SIZE);
  DescriptorWriter& uniform_buffer(uint32_t binding, VkBuffer buffer, VkDeviceSize offset = 0,
                                   VkDeviceSize range = VK_WHOLE_SIZE);
  DescriptorWriter& storage_image(uint32_t binding, VkImageView view);
  DescriptorWriter& uniform_texel_buffer(uint32_t binding, VkBufferView view);
  DescriptorWriter& sampled_image(uint32_t binding, VkImageView view, VkSampler sampler,
                                  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  DescriptorWriter& acceleration_structure(uint32_t binding, VkAccelerationStructureKHR structure);
  void push(const Context& ctx, VkCommandBuffer cmd, const Pipeline& pipeline);

 private:
  struct Entry {
    uint32_t binding;
    VkDescriptorType type;
    VkDescriptorBufferInfo buffer;
    VkDescriptorImageInfo image;
    VkAccelerationStructureKHR structure;
    VkBufferView texel_view;
  };
  std::vector<Entry> entries_;
};

}  // namespace engine::gpu
