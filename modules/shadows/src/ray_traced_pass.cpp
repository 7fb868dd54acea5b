#include "ray_traced_pass.hpp"

#include <algorithm>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "gpu/pipeline.hpp"
#include "gpu/profiler.hpp"
#include "shared/ray_traced.h"

namespace shadows::detail {

using namespace engine::gpu;

namespace {

// An acceleration structure and the buffer that stores it.
struct Structure {
  const Context* ctx = nullptr;
  Buffer storage;
  VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
  VkDeviceAddress address = 0;

  Structure() = default;
  Structure(const Context& c, VkAccelerationStructureTypeKHR type, VkDeviceSize size, const std::string& name)
      : ctx(&c) {
    storage = Buffer(c, size,
                     VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                     false, name);
    VkAccelerationStructureCreateInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    info.buffer = storage.handle();
    info.size = size;
    info.type = type;
    VK_CHECK(c.rt.create_acceleration_structure(c.device(), &info, c.allocator(), &handle));
    VkAccelerationStructureDeviceAddressInfoKHR a{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    a.accelerationStructure = handle;
    address = c.rt.get_acceleration_structure_address(c.device(), &a);
    c.set_name(handle, VK_OBJECT_TYPE_ACCELERATION_STRUCTURE_KHR, name);
  }
  ~Structure() { reset(); }
  Structure(Structure&& o) noexcept { *this = std::move(o); }
  Structure& operator=(Structure&& o) noexcept {
    if (this != &o) {
      reset();
      ctx = o.ctx;
      storage = std::move(o.storage);
      handle = std::exchange(o.handle, VK_NULL_HANDLE);
      address = std::exchange(o.address, 0);
    }
    return *this;
  }
  void reset() {
    if (ctx && handle) {
      // A frame still in flight may trace it (Context::defer_releases); its storage defers alike.
      const Context* c = ctx;
      auto destroy = [c, h = handle] { c->rt.destroy_acceleration_structure(c->device(), h, c->allocator()); };
      if (c->defers_releases()) c->defer_release(destroy);
      else destroy();
    }
    handle = VK_NULL_HANDLE;
    address = 0;
    storage.reset();
  }
};

// A scratch buffer whose device address is rounded up to the device's scratch alignment.
struct Scratch {
  Buffer buffer;
  VkDeviceAddress address = 0;
  void ensure(const Context& ctx, VkDeviceSize bytes, const std::string& name) {
    const VkDeviceSize alignment = std::max<VkDeviceSize>(ctx.features().scratch_offset_alignment, 1);
    if (buffer.valid() && buffer.size() >= bytes + alignment) return;
    buffer = Buffer(ctx, bytes + alignment,
                    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT, false, name);
    address = align_up(buffer.device_address(), alignment);
  }
};

VkTransformMatrixKHR to_transform(const glm::mat4& m) {
  VkTransformMatrixKHR t{};
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) t.matrix[row][col] = m[col][row];  // glm is column-major
  return t;
}

// A fresh build of one geometry, tuned for tracing (both levels are built that way; deformed slots'
// bottom levels may also be updated: kDeformedFlags).
VkAccelerationStructureBuildGeometryInfoKHR build_info(VkAccelerationStructureTypeKHR type,
                                                       const VkAccelerationStructureGeometryKHR& geometry) {
  VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
  info.type = type;
  info.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
  info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
  info.geometryCount = 1;
  info.pGeometries = &geometry;
  return info;
}

// One mesh table entry as bottom-level geometry: opaque triangles straight from the module's shared
// vertex and index buffers (the range's offsets go in the build range).
VkAccelerationStructureGeometryKHR bottom_geometry(const Geometry& geometry, const MeshRange& mesh) {
  VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
  g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
  g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
  auto& tri = g.geometry.triangles;
  tri = {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR};
  tri.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
  tri.vertexData.deviceAddress = geometry.vertices().device_address();  // + firstVertex * stride
  tri.vertexStride = sizeof(StoredVertex);
  tri.maxVertex = mesh.vertex_count - 1;  // relative to firstVertex
  tri.indexType = VK_INDEX_TYPE_UINT32;
  tri.indexData.deviceAddress = geometry.indices().device_address();  // + primitiveOffset
  return g;
}

VkAccelerationStructureBuildRangeInfoKHR bottom_range(const MeshRange& mesh) {
  VkAccelerationStructureBuildRangeInfoKHR range{};
  range.primitiveCount = mesh.index_count / 3;
  range.primitiveOffset = mesh.first_index * uint32_t(sizeof(uint32_t));
  range.firstVertex = uint32_t(mesh.vertex_offset);
  return range;
}

// A deformed slot's bottom level may be refitted (updated in place) to its positions of each frame. Built
// for a fast build: on the lent H200 (100 skinned figures, 1080p) its refit and the trace through it both
// ran faster than with PREFER_FAST_TRACE (rt_build 0.267 against 0.340 ms, rt_trace 0.192 against 0.198).
constexpr VkBuildAccelerationStructureFlagsKHR kDeformedFlags =
    VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;

// The trace's push constants. Rays over the light only at 1 sample per pixel and for a light with a
// size; otherwise extent.w's ray count is 0 and the shader takes the hard path it always took.
gpu_shared::RayTracedPush trace_push(const View& view, uint32_t samples_per_pixel, uint32_t light_samples,
                                     bool collect_stats) {
  gpu_shared::RayTracedPush push{};
  push.inverse_view_projection = view.inverse_view_projection;
  push.light_direction = glm::vec4(glm::normalize(view.light_direction), 0.0f);
  push.light_cone = glm::vec4(0.0f, view.camera_position);  // yzw: the shadow-ray offset's eye
  if (view.local_light) {
    push.light_position = glm::vec4(view.light_position, view.light_range);
    push.light_cone.x = view.light_cos_outer;
  }
  const bool single = samples_per_pixel != 32;
  const float size = view.local_light ? view.light_radius : view.light_tan_half_angle;
  const uint32_t light_rays = single && size > 0.0f ? std::min(light_samples, 64u) : 0u;
  if (light_rays > 0) push.light_direction.w = size;
  push.extent = glm::uvec4(view.extent.width, view.extent.height, single ? 1u : 32u,
                           (collect_stats ? gpu_shared::RT_EXTENT_COUNT_RAYS : 0u) |
                               (light_rays << gpu_shared::RT_EXTENT_LIGHT_RAYS_SHIFT));
  return push;
}

}  // namespace

struct RayTracedPass::Impl {
  Context& ctx;
  Pipeline pipeline;
  ShaderBindingTable sbt;
  // Bottom levels, one per Geometry mesh table entry (empty meshes have none): registered meshes built
  // once, deformed slots built to be refitted (update_offsets: each one's part of update_scratch).
  std::vector<Structure> bottom;
  const Geometry* built_for = nullptr;
  VkBuffer built_vertices = VK_NULL_HANDLE;
  size_t built_entries = 0;
  std::vector<VkDeviceSize> update_offsets;
  Scratch update_scratch;
  std::optional<uint64_t> refitted_frame;  // the frame whose deformed slots are up to date
  Structure top;
  uint32_t top_capacity = 0;
  Scratch top_scratch;
  // Per frame-in-flight slot, written by the host when the slot's frame is recorded:
  std::vector<Buffer> instances;           // VkAccelerationStructureInstanceKHR array
  std::vector<Buffer> instance_materials;  // RayTracedInstance per instance (the any-hit alpha test)
  uint32_t instance_slot = 0;              // the slot of the frame being recorded
  Scratch bottom_scratch;                  // kept until the next bottom-level build (frames in flight)
  Buffer counters;
  ReadbackRing counters_readback;
  uint32_t instance_count = 0;
  uint64_t bottom_triangles = 0;

  explicit Impl(Context& c) : ctx(c) {
    PipelineFactory factory(ctx);
    RayTracingPipelineDesc d;
    d.name = "rt shadow";
    d.raygen_shader = "rt_shadow.rgen";
    d.miss_shaders = {"rt_shadow.rmiss"};
    d.hit_groups = {{"", "rt_shadow.rahit"}};  // occlusion only; the any-hit shader alpha-tests
    d.push_constant_size = sizeof(gpu_shared::RayTracedPush);
    d.bindings = {{gpu_shared::RT_BINDING_SCENE, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR},
                  {gpu_shared::RT_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                  {gpu_shared::RT_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                  {gpu_shared::RT_BINDING_ALBEDO, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                  {gpu_shared::RT_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                  {gpu_shared::RT_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                  {gpu_shared::RT_BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                  {gpu_shared::RT_BINDING_INDICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                  {gpu_shared::RT_BINDING_INSTANCES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                  {gpu_shared::RT_BINDING_MATERIAL_TEXTURES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}};
    pipeline = factory.ray_tracing(d);
    sbt = ShaderBindingTable(ctx, pipeline, 1, 1, "rt shader binding table");
    const VkDeviceSize counter_bytes = gpu_shared::RT_COUNTER_COUNT * sizeof(uint32_t);
    counters = Buffer(ctx, counter_bytes,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                          VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                      false, "rt counters");
  }

  // One bottom level per mesh table entry, built together in the frame's command buffer (deformed
  // slots from their positions of this frame, ready to be refitted; the others once).
  void build_bottom_levels(VkCommandBuffer cmd, const Geometry& geometry) {
    const size_t n = geometry.mesh_count();
    bottom.clear();
    bottom.resize(n);
    update_offsets.assign(n, 0);
    bottom_triangles = 0;
    std::vector<VkAccelerationStructureGeometryKHR> geometries(n);
    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
    std::vector<VkDeviceSize> scratch_offsets;
    VkDeviceSize scratch_total = 0, update_total = 0;
    const VkDeviceSize scratch_alignment = std::max<VkDeviceSize>(ctx.features().scratch_offset_alignment, 1);
    for (uint32_t entry = 0; entry < n; ++entry) {
      const MeshRange& mesh = geometry.mesh(entry);
      if (mesh.index_count < 3 || mesh.vertex_count == 0) continue;
      geometries[entry] = bottom_geometry(geometry, mesh);
      VkAccelerationStructureBuildGeometryInfoKHR info =
          build_info(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, geometries[entry]);
      if (mesh.deformed) info.flags = kDeformedFlags;
      const VkAccelerationStructureBuildRangeInfoKHR range = bottom_range(mesh);
      VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
      ctx.rt.get_build_sizes(ctx.device(), VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, &info, &range.primitiveCount,
                             &sizes);
      bottom[entry] = Structure(ctx, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, sizes.accelerationStructureSize,
                                "rt bottom level " + std::to_string(entry));
      info.dstAccelerationStructure = bottom[entry].handle;
      scratch_offsets.push_back(scratch_total);
      scratch_total += align_up(sizes.buildScratchSize, scratch_alignment);
      if (mesh.deformed) {
        update_offsets[entry] = update_total;
        update_total += align_up(std::max<VkDeviceSize>(sizes.updateScratchSize, 1), scratch_alignment);
      }
      infos.push_back(info);
      ranges.push_back(range);
      bottom_triangles += range.primitiveCount;
    }
    if (update_total > 0) update_scratch.ensure(ctx, update_total, "rt bottom level update scratch");
    if (!infos.empty()) {
      // The structures keep their own storage; the scratch stays until the next build.
      Scratch& scratch = bottom_scratch;
      scratch.ensure(ctx, scratch_total, "rt bottom level build scratch");
      std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> range_pointers;
      for (size_t i = 0; i < infos.size(); ++i) {
        infos[i].scratchData.deviceAddress = scratch.address + scratch_offsets[i];
        range_pointers.push_back(&ranges[i]);
      }
      // Recorded in the frame: the geometry imports before it made the vertices visible to builds,
      // and the top-level build's barrier orders these writes before its reads.
      memory_barrier(cmd, VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                     VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
                     VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                     VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR);
      ctx.rt.cmd_build_acceleration_structures(cmd, uint32_t(infos.size()), infos.data(), range_pointers.data());
    }
    built_for = &geometry;
    built_vertices = geometry.vertices().handle();
    built_entries = n;
  }

  // Refits the bottom levels of the deformed slots this frame's casters draw (mode UPDATE in place) to
  // the positions the frame's deformed import wrote: its barrier made them visible to the builds.
  void refit_deformed(VkCommandBuffer cmd, const Frame& frame) {
    std::vector<uint32_t> entries;
    for (const auto& d : frame.draws)
      if (d.shadow.casts_shadow && d.mesh < bottom.size() && bottom[d.mesh].handle && frame.geometry.mesh(d.mesh).deformed &&
          std::find(entries.begin(), entries.end(), d.mesh) == entries.end())
        entries.push_back(d.mesh);
    if (entries.empty()) return;
    std::vector<VkAccelerationStructureGeometryKHR> geometries;
    geometries.reserve(entries.size());
    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
    for (uint32_t entry : entries) {
      const MeshRange& mesh = frame.geometry.mesh(entry);
      geometries.push_back(bottom_geometry(frame.geometry, mesh));
      VkAccelerationStructureBuildGeometryInfoKHR info =
          build_info(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, geometries.back());
      info.flags = kDeformedFlags;
      info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
      info.srcAccelerationStructure = info.dstAccelerationStructure = bottom[entry].handle;
      info.scratchData.deviceAddress = update_scratch.address + update_offsets[entry];
      infos.push_back(info);
      ranges.push_back(bottom_range(mesh));
    }
    std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> range_pointers;
    for (const auto& range : ranges) range_pointers.push_back(&range);
    // The previous frames' traces and builds reading these structures (and the update scratch) finish
    // before they are rewritten; the top-level build's barrier then orders the refits before its reads.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                   VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
                   VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                   VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR);
    ctx.rt.cmd_build_acceleration_structures(cmd, uint32_t(infos.size()), infos.data(), range_pointers.data());
  }

  // Rebuilds the top level over every casting draw with its transform of this frame.
  void build_top_level(VkCommandBuffer cmd, const Frame& frame) {
    std::vector<VkAccelerationStructureInstanceKHR> list;
    std::vector<gpu_shared::RayTracedInstance> materials;
    list.reserve(frame.draws.size());
    for (const auto& d : frame.draws) {
      if (!d.shadow.casts_shadow || d.mesh >= bottom.size() || !bottom[d.mesh].handle) continue;
      VkAccelerationStructureInstanceKHR inst{};
      inst.transform = to_transform(d.world);
      inst.instanceCustomIndex = uint32_t(list.size());
      inst.mask = 0xff;
      inst.instanceShaderBindingTableRecordOffset = 0;
      // Both faces occlude, as in the reference; only alpha-tested instances run the any-hit shader.
      inst.flags = VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR |
                   (d.alpha_tested() ? VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR : VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR);
      inst.accelerationStructureReference = bottom[d.mesh].address;
      list.push_back(inst);
      const MeshRange& range = frame.geometry.mesh(d.mesh);
      materials.push_back({range.first_index, range.vertex_offset, d.base_color_texture, d.alpha_threshold});
    }
    instance_count = uint32_t(list.size());

    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    g.geometry.instances = {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR};
    g.geometry.instances.arrayOfPointers = VK_FALSE;
    VkAccelerationStructureBuildGeometryInfoKHR info = build_info(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, g);

    // Storage, scratch and the instance array are sized for a capacity that grows (doubling) with
    // the caster count, so a changing scene does not reallocate every frame.
    if (instance_count > top_capacity || !top.handle) {
      top_capacity = std::max<uint32_t>({instance_count, top_capacity * 2, 16});
      VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
      ctx.rt.get_build_sizes(ctx.device(), VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, &info, &top_capacity, &sizes);
      top = Structure(ctx, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize, "rt top level");
      top_scratch.ensure(ctx, sizes.buildScratchSize, "rt top level build scratch");
      instances.clear();
      instance_materials.clear();
    }
    if (instances.size() != frame.slots) {
      instances.resize(frame.slots);
      instance_materials.resize(frame.slots);
    }
    instance_slot = frame.slot;
    Buffer& slot_instances = instances[frame.slot];
    Buffer& slot_materials = instance_materials[frame.slot];
    if (!slot_instances.valid()) {
      slot_instances = Buffer(ctx, VkDeviceSize(top_capacity) * sizeof(VkAccelerationStructureInstanceKHR),
                              VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                  VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                              true, "rt instances");
      slot_materials = Buffer(ctx, VkDeviceSize(top_capacity) * sizeof(gpu_shared::RayTracedInstance),
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "rt instance materials");
    }
    // This slot's frame frames_in_flight ago, the last reader of these, has completed.
    if (!list.empty()) {
      slot_instances.write(list.data(), list.size() * sizeof(list[0]));
      slot_materials.write(materials.data(), materials.size() * sizeof(materials[0]));
    }
    g.geometry.instances.data.deviceAddress = slot_instances.device_address();
    info.dstAccelerationStructure = top.handle;
    info.scratchData.deviceAddress = top_scratch.address;
    VkAccelerationStructureBuildRangeInfoKHR range{};
    range.primitiveCount = instance_count;
    const VkAccelerationStructureBuildRangeInfoKHR* range_pointer = &range;
    // The previous trace's reads of the top level and scratch finish before this build rewrites them.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                   VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
                   VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                   VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR);
    ctx.rt.cmd_build_acceleration_structures(cmd, 1, &info, &range_pointer);
    // The trace reads the finished top level.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
                   VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR, VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR,
                   VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR);
  }
};

RayTracedPass::RayTracedPass(Context& ctx) {
  if (!ctx.features().ray_tracing_pipeline) throw std::runtime_error(ctx.features().ray_tracing_missing);
  impl_ = std::make_unique<Impl>(ctx);
}

RayTracedPass::~RayTracedPass() = default;

void RayTracedPass::scene_changed() {
  impl_->bottom.clear();
  impl_->built_for = nullptr;
}

void RayTracedPass::record(Frame& frame, uint32_t samples_per_pixel, uint32_t light_samples, bool collect_stats) {
  Impl& m = *impl_;
  VkCommandBuffer cmd = frame.cmd;
  // Rebuilt when the vertex buffer moved or the mesh table grew (a mesh registered, a deformed slot
  // made); else the deformed slots drawn are refitted, once a frame (the first of its records).
  const bool rebuild = m.built_for != &frame.geometry || m.built_vertices != frame.geometry.vertices().handle() ||
                       m.built_entries != frame.geometry.mesh_count();
  if (rebuild) m.build_bottom_levels(cmd, frame.geometry);
  {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "rt_build");
    if (!rebuild && m.refitted_frame != frame.view.frame_index) m.refit_deformed(cmd, frame);
    m.refitted_frame = frame.view.frame_index;
    m.build_top_level(cmd, frame);
  }
  if (collect_stats) {
    vkCmdFillBuffer(cmd, m.counters.handle(), 0, VK_WHOLE_SIZE, 0);
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR,
                   VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "rt_trace");
    const gpu_shared::RayTracedPush push = trace_push(frame.view, samples_per_pixel, light_samples, collect_stats);
    m.pipeline.bind(cmd);
    DescriptorWriter()
        .acceleration_structure(gpu_shared::RT_BINDING_SCENE, m.top.handle)
        .storage_image(gpu_shared::RT_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gpu_shared::RT_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .storage_image(gpu_shared::RT_BINDING_ALBEDO, frame.gbuffer.albedo)
        .storage_image(gpu_shared::RT_BINDING_SHADOW_TERM, frame.shadow_term.view())
        .storage_buffer(gpu_shared::RT_BINDING_COUNTERS, m.counters.handle())
        .storage_buffer(gpu_shared::RT_BINDING_VERTICES, frame.geometry.vertices().handle())
        .storage_buffer(gpu_shared::RT_BINDING_INDICES, frame.geometry.indices().handle())
        .storage_buffer(gpu_shared::RT_BINDING_INSTANCES, m.instance_materials[m.instance_slot].handle())
        .storage_buffer(gpu_shared::RT_BINDING_MATERIAL_TEXTURES, frame.geometry.textures().handle())
        .push(m.ctx, cmd, m.pipeline);
    m.pipeline.push_constants(cmd, push);
    m.sbt.trace(m.ctx, cmd, frame.view.extent.width, frame.view.extent.height);
  }
  if (collect_stats) {
    m.counters_readback.record_copy(frame, m.counters, m.counters.size(), VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR,
                                    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, "rt counters readback");
  }
}

void RayTracedPass::after_frame(std::vector<Stats>& records, uint32_t slot) {
  Impl& m = *impl_;
  for (const void* readback : m.counters_readback.take_records(slot)) {
    const auto* c = static_cast<const uint32_t*>(readback);
    Stats& s = records.emplace_back();
    s.rt_instances = m.instance_count;
    s.rt_triangles = m.bottom_triangles;
    s.shading_points = c[gpu_shared::RT_COUNTER_SHADING_POINTS];
    s.lit_candidates = c[gpu_shared::RT_COUNTER_CANDIDATES];
    s.rays_traced = c[gpu_shared::RT_COUNTER_RAYS];
    s.rays_occluded = c[gpu_shared::RT_COUNTER_OCCLUDED];
  }
}

uint32_t RayTracedPass::records_so_far(uint32_t slot, uint64_t frame_index) const {
  return impl_->counters_readback.recorded(slot, frame_index);
}

}  // namespace shadows::detail
