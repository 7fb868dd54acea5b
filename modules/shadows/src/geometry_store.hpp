#pragma once
// Host meshes copied into the module's Geometry on the GPU: register_mesh() validates and queues a
// mesh, the next record() converts it (positions, 16/32-bit indices, uvs, alpha texture) with compute
// passes. Buffers only grow; a replaced buffer outlives the frames in flight that used it
// (engine::gpu::Context::defer_releases).
#include <string>
#include <utility>
#include <vector>

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
