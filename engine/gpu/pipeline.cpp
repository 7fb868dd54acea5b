#include "gpu/pipeline.hpp"

#include <algorithm>
#include <fstream>
#include <mutex>
#include <unistd.h>

namespace engine::gpu {

std::filesystem::path shader_directory() {
  if (const char* env = std::getenv("ENGINE_SHADER_DIR"); env && *env) return env;
  std::error_code ec;
  auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return ENGINE_SHADER_DIR_NAME;
  return exe.parent_path() / ENGINE_SHADER_DIR_NAME;
}

namespace {

struct EmbeddedRegistry {
  std::mutex mutex;
  std::vector<std::span<const EmbeddedShader>> tables;
};

EmbeddedRegistry& embedded_registry() {
  static EmbeddedRegistry registry;
  return registry;
}

// The capabilities a shader declares that depend on an optional feature this device lacks (or has
// masked as absent): a pipeline made from it would be invalid, so the shader is refused in one line
// instead. Capabilities lead a module, after its 5-word header.
void check_capabilities(const Context& ctx, const std::string& name, std::span<const uint32_t> code) {
  constexpr uint32_t kOpCapability = 17, kOpExtension = 10;
  const DeviceFeatures& f = ctx.features();
  struct Needs {
    uint32_t capability;
    bool present;
    const char* what;
  };
  const Needs needs[] = {
      {2, f.geometry_shader, "geometry shaders (Geometry)"},
      {11, f.shader_int64, "64-bit integers (Int64)"},
      {63, f.subgroup_arithmetic_compute_fragment, "subgroup arithmetic and ballot operations"},
      {64, f.subgroup_arithmetic_compute_fragment, "subgroup arithmetic and ballot operations"},
      {4479, f.ray_tracing_pipeline, "ray tracing pipelines (RayTracingKHR)"},
      {5284, f.fragment_shader_barycentric, "fragment_shader_barycentric"},
  };
  for (size_t at = 5; at < code.size();) {
    const uint32_t opcode = code[at] & 0xffffu, words = code[at] >> 16;
    if ((opcode != kOpCapability && opcode != kOpExtension) || words == 0) break;
    if (opcode == kOpCapability && words > 1)
      for (const Needs& n : needs)
        if (code[at + 1] == n.capability && !n.present)
          throw VulkanError("shader " + name + " needs " + n.what + ", which " + ctx.device_name() + " lacks");
    at += words;
  }
}

}  // namespace

void register_embedded_shaders(std::span<const EmbeddedShader> shaders) {
  EmbeddedRegistry& r = embedded_registry();
  std::lock_guard lock(r.mutex);
  const bool known = std::any_of(r.tables.begin(), r.tables.end(),
                                 [&](std::span<const EmbeddedShader> t) { return t.data() == shaders.data(); });
  if (!known) r.tables.push_back(shaders);
}

std::span<const uint32_t> embedded_shader(const std::string& name) {
  EmbeddedRegistry& r = embedded_registry();
  std::lock_guard lock(r.mutex);
  for (std::span<const EmbeddedShader> table : r.tables)
    for (const EmbeddedShader& s : table)
      if (name == s.name) return s.code;
  return {};
}

ShaderModule::ShaderModule(const Context& ctx, const std::string& name) : ctx_(ctx) {
  if (const std::span<const uint32_t> embedded = embedded_shader(name); !embedded.empty()) {
    check_capabilities(ctx, name, embedded);
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = embedded.size_bytes();
    info.pCode = embedded.data();
    VK_CHECK(vkCreateShaderModule(ctx.device(), &info, ctx.allocator(), &module_));
    ctx.set_name(module_, VK_OBJECT_TYPE_SHADER_MODULE, name);
    return;
  }
  const auto path = shader_directory() / (name + ".spv");
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) throw VulkanError("cannot open shader " + path.string() + " (was the project built?)");
  const auto size = static_cast<size_t>(file.tellg());
  if (size == 0 || size % 4 != 0) throw VulkanError("shader " + path.string() + " is not valid SPIR-V");
  std::vector<uint32_t> code(size / 4);
  file.seekg(0);
  file.read(reinterpret_cast<char*>(code.data()), static_cast<std::streamsize>(size));
  check_capabilities(ctx, name, code);
  VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  info.codeSize = size;
  info.pCode = code.data();
  VK_CHECK(vkCreateShaderModule(ctx.device(), &info, ctx.allocator(), &module_));
  ctx.set_name(module_, VK_OBJECT_TYPE_SHADER_MODULE, name);
}

ShaderModule::~ShaderModule() {
  if (module_) vkDestroyShaderModule(ctx_.device(), module_, ctx_.allocator());
}

Pipeline& Pipeline::operator=(Pipeline&& o) noexcept {
  if (this != &o) {
    reset();
    ctx_ = o.ctx_;
    pipeline_ = std::exchange(o.pipeline_, VK_NULL_HANDLE);
    layout_ = std::exchange(o.layout_, VK_NULL_HANDLE);
    set_layout_ = std::exchange(o.set_layout_, VK_NULL_HANDLE);
    bind_point_ = o.bind_point_;
  }
  return *this;
}

void Pipeline::reset() {
  if (!ctx_) return;
  VkDevice d = ctx_->device();
  if (pipeline_) vkDestroyPipeline(d, pipeline_, ctx_->allocator());
  if (layout_) vkDestroyPipelineLayout(d, layout_, ctx_->allocator());
  if (set_layout_) vkDestroyDescriptorSetLayout(d, set_layout_, ctx_->allocator());
  pipeline_ = VK_NULL_HANDLE;
  layout_ = VK_NULL_HANDLE;
  set_layout_ = VK_NULL_HANDLE;
}

void PipelineFactory::make_layout(Pipeline& p, const std::vector<Binding>& bindings, uint32_t push_size) const {
  p.ctx_ = &ctx_;
  std::vector<VkDescriptorSetLayoutBinding> vk_bindings;
  for (const auto& b : bindings) vk_bindings.push_back({b.binding, b.type, 1, b.stages, nullptr});
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  set_info.bindingCount = static_cast<uint32_t>(vk_bindings.size());
  set_info.pBindings = vk_bindings.data();
  VK_CHECK(vkCreateDescriptorSetLayout(ctx_.device(), &set_info, ctx_.allocator(), &p.set_layout_));
  VkPushConstantRange range{VK_SHADER_STAGE_ALL, 0, push_size};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &p.set_layout_;
  layout_info.pushConstantRangeCount = push_size ? 1 : 0;
  layout_info.pPushConstantRanges = &range;
  VK_CHECK(vkCreatePipelineLayout(ctx_.device(), &layout_info, ctx_.allocator(), &p.layout_));
}

namespace {
struct Specialization {
  std::vector<VkSpecializationMapEntry> entries;
  std::vector<uint32_t> data;
  VkSpecializationInfo info{};
  explicit Specialization(const std::vector<SpecializationConstant>& constants) {
    for (size_t i = 0; i < constants.size(); ++i) {
      entries.push_back({constants[i].id, static_cast<uint32_t>(i * 4), 4});
      data.push_back(constants[i].value);
    }
    info.mapEntryCount = static_cast<uint32_t>(entries.size());
    info.pMapEntries = entries.data();
    info.dataSize = data.size() * 4;
    info.pData = data.data();
  }
  const VkSpecializationInfo* get() const { return entries.empty() ? nullptr : &info; }
};

// A pipeline's shader stages; the modules live until the pipeline is created.
struct ShaderStages {
  const Context& ctx;
  const VkSpecializationInfo* specialization;
  std::vector<std::unique_ptr<ShaderModule>> modules;
  std::vector<VkPipelineShaderStageCreateInfo> stages;
  // The new stage's index, or VK_SHADER_UNUSED_KHR when `name` is empty (no shader).
  uint32_t add(const std::string& name, VkShaderStageFlagBits stage) {
    if (name.empty()) return VK_SHADER_UNUSED_KHR;
    modules.push_back(std::make_unique<ShaderModule>(ctx, name));
    VkPipelineShaderStageCreateInfo s{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    s.stage = stage;
    s.module = modules.back()->handle();
    s.pName = "main";
    s.pSpecializationInfo = specialization;
    stages.push_back(s);
    return static_cast<uint32_t>(stages.size() - 1);
  }
};
}  // namespace

Pipeline PipelineFactory::compute(const ComputePipelineDesc& desc) const {
  Pipeline p;
  make_layout(p, desc.bindings, desc.push_constant_size);
  p.bind_point_ = VK_PIPELINE_BIND_POINT_COMPUTE;
  ShaderModule module(ctx_, desc.shader);
  Specialization spec(desc.specialization);
  VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.stage.module = module.handle();
  info.stage.pName = "main";
  info.stage.pSpecializationInfo = spec.get();
  info.layout = p.layout_;
  VK_CHECK(vkCreateComputePipelines(ctx_.device(), ctx_.pipeline_cache(), 1, &info, ctx_.allocator(), &p.pipeline_));
  ctx_.set_name(p.pipeline_, VK_OBJECT_TYPE_PIPELINE, desc.shader);
  return p;
}

Pipeline PipelineFactory::graphics(const GraphicsPipelineDesc& desc) const {
  Pipeline p;
  make_layout(p, desc.bindings, desc.push_constant_size);
  p.bind_point_ = VK_PIPELINE_BIND_POINT_GRAPHICS;
  Specialization spec(desc.specialization);

  ShaderStages shaders{ctx_, spec.get(), {}, {}};
  shaders.add(desc.vertex_shader, VK_SHADER_STAGE_VERTEX_BIT);
  shaders.add(desc.geometry_shader, VK_SHADER_STAGE_GEOMETRY_BIT);
  shaders.add(desc.fragment_shader, VK_SHADER_STAGE_FRAGMENT_BIT);

  VkVertexInputBindingDescription vb{0, kStandardVertexStride, VK_VERTEX_INPUT_RATE_VERTEX};
  VkVertexInputAttributeDescription attrs[3] = {
      {0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0},   // position
      {1, 0, VK_FORMAT_R32G32B32_SFLOAT, 12},  // normal
      {2, 0, VK_FORMAT_R32G32_SFLOAT, 24},     // uv
  };
  VkPipelineVertexInputStateCreateInfo vertex_input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  if (desc.vertex_input != VertexInput::None) {
    vertex_input.vertexBindingDescriptionCount = 1;
    vertex_input.pVertexBindingDescriptions = &vb;
    vertex_input.vertexAttributeDescriptionCount = desc.vertex_input == VertexInput::PositionOnly ? 1 : 3;
    vertex_input.pVertexAttributeDescriptions = attrs;
  }
  VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  assembly.topology = desc.topology;
  VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  viewport.viewportCount = 1;
  viewport.scissorCount = 1;

  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.polygonMode = VK_POLYGON_MODE_FILL;
  raster.cullMode = desc.cull_mode;
  raster.frontFace = desc.front_face;
  raster.lineWidth = 1.0f;
  raster.depthClampEnable = desc.depth_clamp;
  raster.depthBiasEnable = desc.depth_bias;
  raster.depthBiasConstantFactor = desc.depth_bias_constant;
  raster.depthBiasSlopeFactor = desc.depth_bias_slope;
  VkPipelineRasterizationConservativeStateCreateInfoEXT conservative{
      VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_CONSERVATIVE_STATE_CREATE_INFO_EXT};
  if (desc.conservative != ConservativeMode::Off) {
    if (!ctx_.features().conservative_rasterization)
      throw VulkanError("pipeline " + desc.name + " needs VK_EXT_conservative_rasterization, which this device lacks");
    conservative.conservativeRasterizationMode = desc.conservative == ConservativeMode::Overestimate
                                                     ? VK_CONSERVATIVE_RASTERIZATION_MODE_OVERESTIMATE_EXT
                                                     : VK_CONSERVATIVE_RASTERIZATION_MODE_UNDERESTIMATE_EXT;
    conservative.extraPrimitiveOverestimationSize = desc.conservative_extra_size;
    raster.pNext = &conservative;
  }

  VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  depth.depthTestEnable = desc.depth_test && desc.depth_format != VK_FORMAT_UNDEFINED;
  depth.depthWriteEnable = desc.depth_write && desc.depth_format != VK_FORMAT_UNDEFINED;
  depth.depthCompareOp = desc.depth_compare;

  std::vector<VkPipelineColorBlendAttachmentState> blends(desc.color_formats.size());
  for (auto& b : blends) {
    b.colorWriteMask = desc.color_write ? (VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                                           VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT)
                                        : 0;
    if (desc.alpha_blend) {
      b.blendEnable = VK_TRUE;
      b.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
      b.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
      b.colorBlendOp = VK_BLEND_OP_ADD;
      b.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
      b.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
      b.alphaBlendOp = VK_BLEND_OP_ADD;
    }
  }
  VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  blend.attachmentCount = static_cast<uint32_t>(blends.size());
  blend.pAttachments = blends.data();

  // With depth bias on, the bias values are dynamic so settings can change without a rebuild.
  std::vector<VkDynamicState> dynamic_states = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  if (desc.depth_bias) dynamic_states.push_back(VK_DYNAMIC_STATE_DEPTH_BIAS);
  if (desc.dynamic_depth_compare) dynamic_states.push_back(VK_DYNAMIC_STATE_DEPTH_COMPARE_OP);
  VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dynamic.dynamicStateCount = static_cast<uint32_t>(dynamic_states.size());
  dynamic.pDynamicStates = dynamic_states.data();

  VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  rendering.colorAttachmentCount = static_cast<uint32_t>(desc.color_formats.size());
  rendering.pColorAttachmentFormats = desc.color_formats.data();
  rendering.depthAttachmentFormat = desc.depth_format;

  VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  info.pNext = &rendering;
  info.stageCount = static_cast<uint32_t>(shaders.stages.size());
  info.pStages = shaders.stages.data();
  info.pVertexInputState = &vertex_input;
  info.pInputAssemblyState = &assembly;
  info.pViewportState = &viewport;
  info.pRasterizationState = &raster;
  info.pMultisampleState = &multisample;
  info.pDepthStencilState = &depth;
  info.pColorBlendState = &blend;
  info.pDynamicState = &dynamic;
  info.layout = p.layout_;
  VK_CHECK(vkCreateGraphicsPipelines(ctx_.device(), ctx_.pipeline_cache(), 1, &info, ctx_.allocator(), &p.pipeline_));
  ctx_.set_name(p.pipeline_, VK_OBJECT_TYPE_PIPELINE, desc.name.empty() ? desc.vertex_shader : desc.name);
  return p;
}

Pipeline PipelineFactory::ray_tracing(const RayTracingPipelineDesc& desc) const {
  if (!ctx_.features().ray_tracing_pipeline) throw VulkanError(ctx_.features().ray_tracing_missing);
  Pipeline p;
  make_layout(p, desc.bindings, desc.push_constant_size);
  p.bind_point_ = VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR;
  Specialization spec(desc.specialization);
  ShaderStages shaders{ctx_, spec.get(), {}, {}};
  auto general_group = [](uint32_t stage) {
    VkRayTracingShaderGroupCreateInfoKHR g{VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR};
    g.type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
    g.generalShader = stage;
    g.closestHitShader = g.anyHitShader = g.intersectionShader = VK_SHADER_UNUSED_KHR;
    return g;
  };
  std::vector<VkRayTracingShaderGroupCreateInfoKHR> groups;
  groups.push_back(general_group(shaders.add(desc.raygen_shader, VK_SHADER_STAGE_RAYGEN_BIT_KHR)));
  for (const auto& miss : desc.miss_shaders) groups.push_back(general_group(shaders.add(miss, VK_SHADER_STAGE_MISS_BIT_KHR)));
  for (const auto& hit : desc.hit_groups) {
    VkRayTracingShaderGroupCreateInfoKHR g{VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR};
    g.type = VK_RAY_TRACING_SHADER_GROUP_TYPE_TRIANGLES_HIT_GROUP_KHR;
    g.generalShader = g.intersectionShader = VK_SHADER_UNUSED_KHR;
    g.closestHitShader = shaders.add(hit.closest_hit, VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR);
    g.anyHitShader = shaders.add(hit.any_hit, VK_SHADER_STAGE_ANY_HIT_BIT_KHR);
    groups.push_back(g);
  }
  VkRayTracingPipelineCreateInfoKHR info{VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR};
  info.stageCount = static_cast<uint32_t>(shaders.stages.size());
  info.pStages = shaders.stages.data();
  info.groupCount = static_cast<uint32_t>(groups.size());
  info.pGroups = groups.data();
  info.maxPipelineRayRecursionDepth = desc.max_recursion_depth;
  info.layout = p.layout_;
  VK_CHECK(ctx_.rt.create_ray_tracing_pipelines(ctx_.device(), VK_NULL_HANDLE, ctx_.pipeline_cache(), 1, &info,
                                                ctx_.allocator(),
                                                &p.pipeline_));
  ctx_.set_name(p.pipeline_, VK_OBJECT_TYPE_PIPELINE, desc.name.empty() ? desc.raygen_shader : desc.name);
  return p;
}

ShaderBindingTable::ShaderBindingTable(const Context& ctx, const Pipeline& pipeline, uint32_t miss_count,
                                       uint32_t hit_count, const std::string& name) {
  const auto& f = ctx.features();
  const uint32_t group_count = 1 + miss_count + hit_count;
  const VkDeviceSize handle_size = f.shader_group_handle_size;
  const VkDeviceSize stride = align_up(handle_size, f.shader_group_handle_alignment);
  const VkDeviceSize base = f.shader_group_base_alignment;
  std::vector<uint8_t> handles(size_t(group_count) * handle_size);
  VK_CHECK(ctx.rt.get_shader_group_handles(ctx.device(), pipeline.handle(), 0, group_count, handles.size(),
                                           handles.data()));
  // Region offsets relative to an aligned start; the buffer gets `base` bytes of slack so its device
  // address can be rounded up to the base alignment whatever the allocation's own alignment.
  const VkDeviceSize raygen_offset = 0;
  const VkDeviceSize miss_offset = align_up(raygen_offset + stride, base);
  const VkDeviceSize hit_offset = align_up(miss_offset + stride * miss_count, base);
  const VkDeviceSize total = hit_offset + stride * hit_count;
  buffer_ = Buffer(ctx, total + base,
                   VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT, true,
                   name);
  const VkDeviceAddress start = align_up(buffer_.device_address(), base);
  const VkDeviceSize shift = start - buffer_.device_address();
  auto copy = [&](uint32_t group, VkDeviceSize offset) {
    buffer_.write(handles.data() + size_t(group) * handle_size, handle_size, shift + offset);
  };
  copy(0, raygen_offset);
  for (uint32_t i = 0; i < miss_count; ++i) copy(1 + i, miss_offset + stride * i);
  for (uint32_t i = 0; i < hit_count; ++i) copy(1 + miss_count + i, hit_offset + stride * i);
  // The ray generation region's size must equal its stride.
  raygen_ = {start + raygen_offset, stride, stride};
  miss_ = {miss_count ? start + miss_offset : 0, stride, stride * miss_count};
  hit_ = {hit_count ? start + hit_offset : 0, stride, stride * hit_count};
}

void ShaderBindingTable::trace(const Context& ctx, VkCommandBuffer cmd, uint32_t width, uint32_t height) const {
  ctx.rt.cmd_trace_rays(cmd, &raygen_, &miss_, &hit_, &callable_, width, height, 1);
}

DescriptorWriter& DescriptorWriter::acceleration_structure(uint32_t binding, VkAccelerationStructureKHR structure) {
  entries_.push_back({binding, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, {}, {}, structure, VK_NULL_HANDLE});
  return *this;
}

DescriptorWriter& DescriptorWriter::storage_buffer(uint32_t binding, VkBuffer buffer, VkDeviceSize offset,
                                                   VkDeviceSize range) {
  entries_.push_back({binding, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, {buffer, offset, range}, {}, VK_NULL_HANDLE, VK_NULL_HANDLE});
  return *this;
}
DescriptorWriter& DescriptorWriter::uniform_buffer(uint32_t binding, VkBuffer buffer, VkDeviceSize offset,
                                                   VkDeviceSize range) {
  entries_.push_back({binding, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, {buffer, offset, range}, {}, VK_NULL_HANDLE, VK_NULL_HANDLE});
  return *this;
}
DescriptorWriter& DescriptorWriter::storage_image(uint32_t binding, VkImageView view) {
  entries_.push_back({binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, {}, {VK_NULL_HANDLE, view, VK_IMAGE_LAYOUT_GENERAL}, VK_NULL_HANDLE, VK_NULL_HANDLE});
  return *this;
}
DescriptorWriter& DescriptorWriter::uniform_texel_buffer(uint32_t binding, VkBufferView view) {
  entries_.push_back({binding, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, {}, {}, VK_NULL_HANDLE, view});
  return *this;
}
DescriptorWriter& DescriptorWriter::sampled_image(uint32_t binding, VkImageView view, VkSampler sampler,
                                                  VkImageLayout layout) {
  entries_.push_back({binding, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, {}, {sampler, view, layout}, VK_NULL_HANDLE, VK_NULL_HANDLE});
  return *this;
}

void DescriptorWriter::push(const Context& ctx, VkCommandBuffer cmd, const Pipeline& pipeline) {
  std::vector<VkWriteDescriptorSet> writes;
  writes.reserve(entries_.size());
  // Acceleration structure writes point at these; reserved so the pointers stay put.
  std::vector<VkWriteDescriptorSetAccelerationStructureKHR> structures;
  structures.reserve(entries_.size());
  for (auto& e : entries_) {
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstBinding = e.binding;
    w.descriptorCount = 1;
    w.descriptorType = e.type;
    if (e.type == VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR) {
      VkWriteDescriptorSetAccelerationStructureKHR as{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR};
      as.accelerationStructureCount = 1;
      as.pAccelerationStructures = &e.structure;
      structures.push_back(as);
      w.pNext = &structures.back();
    } else if (e.type == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER || e.type == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER)
      w.pBufferInfo = &e.buffer;
    else if (e.type == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER)
      w.pTexelBufferView = &e.texel_view;
    else
      w.pImageInfo = &e.image;
    writes.push_back(w);
  }
  ctx.cmd_push_descriptor_set(cmd, pipeline.bind_point(), pipeline.layout(), 0,
                              static_cast<uint32_t>(writes.size()), writes.data());
  entries_.clear();
}

}  // namespace engine::gpu
