#pragma once
// Host meshes copied into the module's Geometry on the GPU: register_mesh() validates and queues a
// mesh, the next record() converts it (positions, 16/32-bit indices, uvs, alpha texture) with compute
// passes. Buffers only grow; a replaced buffer is retired until the frames in flight that used it end.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/gpu/pipeline.hpp"
#include "frame.hpp"
#include "shadows/context.hpp"

namespace shadows::detail {

// Objects that frames in flight may still use, released once the frame that last used them is done.
class RetireQueue {
 public:
  template <typename T>
  void retire(uint64_t last_frame, T&& object) {
    if (!object.valid()) return;
    auto held = std::make_shared<T>(std::move(object));
    items_.push_back({last_frame, [held]() mutable { held.reset(); }});
  }
  void release_through(uint64_t completed_frame);
  void release_all() { items_.clear(); }

 private:
  struct Item {
    uint64_t frame;
    std::function<void()> release;
  };
  std::vector<Item> items_;
};

struct MeshInfo {
  std::string name;
  uint32_t alpha_threshold = 0;
  uint32_t texture = 0xffffffffu;
  engine::Aabb bounds;  // object space; invalid: unbounded
  bool live = false;
};

class GeometryStore {
 public:
  void init(engine::gpu::Context& ctx, bool ray_tracing);
  MeshId add(const MeshDesc& mesh);  // throws shadows::Error naming the field
  void remove(MeshId mesh);
  const MeshInfo* find(MeshId mesh) const;
  // Records the queued imports into `cmd` (frame `frame`); replaced buffers go to `retire`.
  void record_imports(VkCommandBuffer cmd, uint64_t frame, RetireQueue& retire);
  Geometry& geometry() { return geometry_; }
  bool has_pending() const { return !pending_.empty(); }

 private:
  struct Pending {
    MeshId id;
    MeshDesc desc;
    uint32_t texture_first_word = 0;
  };
  void grow(engine::gpu::Buffer& buffer, VkDeviceSize bytes, VkDeviceSize used, VkBufferUsageFlags usage,
            const char* name, VkCommandBuffer cmd, uint64_t frame, RetireQueue& retire);

  engine::gpu::Context* ctx_ = nullptr;
  VkBufferUsageFlags geometry_usage_ = 0;
  VkPipelineStageFlags2 extra_reader_stages_ = 0;
  Geometry geometry_;
  std::vector<MeshInfo> meshes_;
  std::vector<Pending> pending_;
  uint32_t vertex_count_ = 0, index_count_ = 0;
  uint32_t texture_count_ = 0, texel_words_ = 0;
  engine::gpu::Pipeline import_;
  engine::gpu::Pipeline texture_import_;
  engine::gpu::Sampler nearest_;
};

// The least alpha byte an alpha test keeps: `scale * byte / 255 >= cutoff` (engine::alpha_threshold's
// rule, so host and engine materials test alike); 256 keeps nothing.
uint32_t alpha_threshold(float cutoff, float scale);

}  // namespace shadows::detail
