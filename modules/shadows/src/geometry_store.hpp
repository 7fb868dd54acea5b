#pragma once
// Host meshes copied into the module's Geometry on the GPU: register_mesh() validates and queues a
// mesh, the next record() converts it (positions, 16/32-bit indices, uvs, alpha texture) with compute
// passes. Buffers only grow; a replaced buffer outlives the frames in flight that used it
// (engine::gpu::Context::defer_releases).
// Deformed instances (Instance::deformed) draw from deformed slots: per mesh, regions of the vertex
// buffer of their own, each a mesh table entry with the mesh's indices. The k-th deformed instance of a
// mesh in a frame uses its k-th slot, made on first need (the buffer grown, the mesh's stored vertices
// copied in for their uvs); every frame the instance's host positions are imported into it. Slots are
// never freed (as meshes' space is not): their count is the most deformed instances of the mesh in any
// one frame so far.
#include <string>
#include <utility>
#include <vector>

#include <shared/host.h>

#include "gpu/pipeline.hpp"
#include "frame.hpp"
#include "shadows/context.hpp"

namespace shadows::detail {

struct MeshInfo {
  std::string name;
  uint32_t alpha_threshold = 0;
  uint32_t texture = 0xffffffffu;
  Aabb bounds;  // object space; invalid: unbounded
  bool live = false;
  uint32_t vertex_count = 0;
  uint32_t entry = 0;                   // its Geometry mesh table entry
  std::vector<uint32_t> deformed_slots;  // the table entries of its deformed slots, in order
};

class GeometryStore {
 public:
  void init(engine::gpu::Context& ctx, bool ray_tracing);
  // Throws shadows::Error naming the field. A mesh without bounds has them computed on the device
  // first (a submission to the adopted queue, waited for).
  MeshId add(const MeshDesc& mesh);
  void remove(MeshId mesh);
  const MeshInfo* find(MeshId mesh) const;
  // Records the queued imports into `cmd`.
  void record_imports(VkCommandBuffer cmd);
  // After record_imports(): gives each deformed instance of the frame its slot (made where missing) and
  // records the import of its host positions there, between barriers ordering the vertex buffer's
  // earlier readers before the writes and the writes before this frame's readers. Returns, per
  // instance, the mesh table entry it draws (its slot, or its mesh's); valid until the next call.
  const std::vector<uint32_t>& record_deformed(VkCommandBuffer cmd, const Instance* instances, uint32_t count);
  Geometry& geometry() { return geometry_; }

 private:
  struct Pending {
    MeshId id;
    MeshDesc desc;
    uint32_t texture_first_word = 0;
  };
  void grow_for_pending(VkCommandBuffer cmd);
  void import_mesh(VkCommandBuffer cmd, const Pending& p);
  void import_textures(VkCommandBuffer cmd);
  // The frame's table entries (entries_), new slots made; returns the first new slot's vertex (or vertex_count_).
  uint32_t assign_entries(const Instance* instances, uint32_t count, std::vector<std::pair<uint32_t, uint32_t>>& fresh);
  void import_positions(VkCommandBuffer cmd, const DeformedPositions& in, const MeshRange& slot);
  gpu_shared::MeshImportPush bind_positions(VkCommandBuffer cmd, const BufferInput& in, uint32_t stride, uint32_t count,
                                            uint32_t mode);
  void grow(engine::gpu::Buffer& buffer, VkDeviceSize bytes, VkDeviceSize used, VkBufferUsageFlags usage,
            const char* name, VkCommandBuffer cmd);

  VkPipelineStageFlags2 geometry_readers() const;
  Aabb device_bounds(const MeshDesc& mesh, const std::string& what);
  // A host region bound at its offset rounded down to the device's alignment; the shader starts `word` in.
  std::pair<VkDeviceSize, VkDeviceSize> bind_region(const BufferInput& in, uint32_t& word) const;
  // Pushes the import pass's five buffers: the source region, the uv region (in a pass reading no
  // uvs, the source again) and the module's vertex, index and bounds buffers.
  void push_import_buffers(VkCommandBuffer cmd, VkBuffer source, VkDeviceSize base, VkDeviceSize range,
                           VkBuffer uvs, VkDeviceSize uv_base, VkDeviceSize uv_range);

  engine::gpu::Context* ctx_ = nullptr;
  VkBufferUsageFlags geometry_usage_ = 0;
  Geometry geometry_;
  std::vector<MeshInfo> meshes_;
  std::vector<Pending> pending_;
  std::vector<uint32_t> entries_;  // record_deformed()'s answer
  uint32_t vertex_count_ = 0, index_count_ = 0;
  uint32_t texture_count_ = 0, texel_words_ = 0;
  engine::gpu::Pipeline import_;
  engine::gpu::Pipeline texture_import_;
  engine::gpu::Sampler nearest_;
  // MESH_IMPORT_BINDING_BOUNDS: the bounds dispatch's result, read back by the CPU (bound, unused, by
  // the other import dispatches).
  engine::gpu::Buffer bounds_;
};

}  // namespace shadows::detail
