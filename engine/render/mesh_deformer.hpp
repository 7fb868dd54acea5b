#pragma once
// The deformable entities' vertices for each frame (SceneGeometry::deformed()): update() poses them
// on the CPU (joint matrices, morph weights, conservative bounds) into the frame slot's pose buffer,
// record() runs skinning.comp for each into its own copy of the vertices before the G-buffer.
#include <vector>

#include "engine/render/renderer.hpp"

namespace engine {

class MeshDeformer {
 public:
  MeshDeformer(gpu::Context& ctx, uint32_t frames_in_flight);
  // Poses every deformed entity of `geometry` for the registry's current transforms and weights
  // (after update_world_transforms), into slot `slot`'s pose buffer (the frame that used it last has
  // completed).
  void update(const Registry& registry, const SceneGeometry& geometry, uint32_t slot);
  // The object-space box around deformed entity i's vertices in the last update().
  const Aabb& bounds(uint32_t i) const { return bounds_.at(i); }
  // Records the deformation of every deformed entity with slot `slot`'s poses, ordered after the
  // previous frames' reads of the vertices and before this frame's (vertex and compute shaders).
  void record(VkCommandBuffer cmd, gpu::GpuProfiler& profiler, const SceneGeometry& geometry, uint32_t slot);

 private:
  struct Job {
    bool posed = false;  // false: the entity has no mesh any more; nothing is dispatched for it
    uint32_t joint_float = 0;
    uint32_t weight_float = 0;
  };
  gpu::Context& ctx_;
  gpu::Pipeline pipeline_;
  std::vector<gpu::Buffer> poses_;  // per frame slot, host-visible
  std::vector<Job> jobs_;
  std::vector<Aabb> bounds_;
  std::vector<float> staging_;
};

}  // namespace engine
