#include "mesh_deformer.hpp"

#include <algorithm>
#include <string>

#include "engine/core/skinning.hpp"
#include "shared/skinning.h"

namespace engine {

using namespace gpu;

MeshDeformer::MeshDeformer(gpu::Context& ctx, uint32_t frames_in_flight) : ctx_(ctx), poses_(frames_in_flight) {
  PipelineFactory factory(ctx);
  pipeline_ = factory.compute({"skinning.comp",
                               {{gpu_shared::SKINNING_BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                {gpu_shared::SKINNING_BINDING_DEFORM_DATA, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                {gpu_shared::SKINNING_BINDING_POSE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
                               sizeof(gpu_shared::SkinningPush)});
}

void MeshDeformer::update(const Registry& registry, const SceneGeometry& geometry, uint32_t slot) {
  const auto& deformed = geometry.deformed();
  jobs_.assign(deformed.size(), {});
  bounds_.assign(deformed.size(), {});
  staging_.clear();
  for (size_t i = 0; i < deformed.size(); ++i) {
    const DeformedMesh& d = deformed[i];
    const Mesh* mesh = registry.try_get<Mesh>(d.entity);
    // An entity destroyed or stripped of its mesh since the scene was set keeps its last pose: its
    // slot is drawn by nobody.
    if (!mesh || !mesh->data) continue;
    std::vector<glm::mat4> joints;
    if (d.skin_word != UINT32_MAX) joints = joint_matrices(registry, d.entity);
    // A skeleton that lost joints since the scene was set keeps the pass inside its data: the
    // missing ones stay at the identity.
    joints.resize(d.joint_count, glm::mat4(1.0f));
    std::vector<float> weights;
    if (const auto* w = registry.try_get<MorphWeights>(d.entity)) weights = w->weights;
    else if (mesh->data->deform) weights = mesh->data->deform->default_weights;
    weights.resize(d.target_count, 0.0f);
    jobs_[i].posed = true;
    jobs_[i].joint_float = uint32_t(staging_.size());
    for (const glm::mat4& m : joints) staging_.insert(staging_.end(), &m[0][0], &m[0][0] + 16);
    jobs_[i].weight_float = uint32_t(staging_.size());
    staging_.insert(staging_.end(), weights.begin(), weights.end());
    bounds_[i] = deformed_bounds(*mesh->data, weights, joints);
  }
  if (deformed.empty()) return;
  if (staging_.empty()) staging_.push_back(0.0f);  // a valid binding for entities with neither
  Buffer& pose = poses_.at(slot);
  const VkDeviceSize bytes = staging_.size() * sizeof(float);
  if (!pose.valid() || pose.size() < bytes)
    pose = Buffer(ctx_, std::max<VkDeviceSize>(bytes, 4096), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true,
                  "pose " + std::to_string(slot));
  pose.write(staging_.data(), bytes);
}

void MeshDeformer::record(VkCommandBuffer cmd, gpu::GpuProfiler& profiler, const SceneGeometry& geometry,
                          uint32_t slot) {
  const auto& deformed = geometry.deformed();
  if (deformed.empty() || jobs_.size() != deformed.size()) return;
  ScopedGpuRegion region(ctx_, profiler, cmd, "deform");
  // The previous frames' G-buffer (vertex shader) and shadow module (compute) reads of these vertices
  // come before they are rewritten.
  const VkPipelineStageFlags2 readers = VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
  memory_barrier(cmd, readers, VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                 VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  pipeline_.bind(cmd);
  DescriptorWriter()
      .storage_buffer(gpu_shared::SKINNING_BINDING_VERTICES, geometry.vertices().handle())
      .storage_buffer(gpu_shared::SKINNING_BINDING_DEFORM_DATA, geometry.deform_data().handle())
      .storage_buffer(gpu_shared::SKINNING_BINDING_POSE, poses_.at(slot).handle())
      .push(ctx_, cmd, pipeline_);
  for (size_t i = 0; i < deformed.size(); ++i) {
    const DeformedMesh& d = deformed[i];
    if (!jobs_[i].posed) continue;
    const GpuMeshRange& own = geometry.mesh(d.mesh);
    const GpuMeshRange& rest = geometry.mesh(d.rest_mesh);
    gpu_shared::SkinningPush push{};
    push.rest_vertex = uint32_t(rest.vertex_offset);
    push.target_vertex = uint32_t(own.vertex_offset);
    push.vertex_count = own.vertex_count;
    push.skin_word = d.skin_word == UINT32_MAX ? gpu_shared::kNoSkin : d.skin_word;
    push.morph_word = d.morph_word;
    push.target_count = d.target_count;
    push.joint_float = jobs_[i].joint_float;
    push.weight_float = jobs_[i].weight_float;
    pipeline_.push_constants(cmd, push);
    vkCmdDispatch(cmd, (own.vertex_count + 63) / 64, 1, 1);
  }
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, readers,
                 VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

}  // namespace engine
