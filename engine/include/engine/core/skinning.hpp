#pragma once
// Deforming meshes: glTF skins (linear blend skinning, 4 joints a vertex) and morph targets, the
// ECS components that pose them, and keyframe animation clips that drive them. The renderer deforms
// on the GPU (skinning.comp); deform_vertices() is the same arithmetic on the CPU for the reference
// and the tests, so both see the same triangles.
//
// A deformable mesh's vertices are deformed in its entity's object space: morph first
// (p = p_rest + sum_k w_k * dp_k, likewise the normal), then skinning
// (p' = sum_j weight_j * J[joint_j] * p, J from joint_matrices()), and the entity's world matrix places
// the result as it places a rigid mesh.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/components.hpp"

namespace engine {

constexpr uint32_t kMaxJointsPerVertex = 4;

// One glTF morph target: per-vertex displacements (as many as MeshData::vertices; normal_deltas empty
// when the target has none).
struct MorphTarget {
  std::string name;
  std::vector<glm::vec3> position_deltas;
  std::vector<glm::vec3> normal_deltas;
};

// What makes a MeshData deformable (MeshData::deform, null for rigid meshes). joints/weights are
// empty, or one entry per vertex: indices into the entity's Skeleton::joints and weights >= 0 that sum
// to 1 (the loader normalises them).
struct DeformData {
  std::vector<glm::uvec4> joints;
  std::vector<glm::vec4> weights;
  uint32_t joint_count = 0;  // every joints[i][k] with weights[i][k] > 0 is below this
  std::vector<MorphTarget> morph_targets;
  std::vector<float> default_weights;  // glTF mesh.weights (one per morph target; 0 where absent)
  // Per joint: the object-space box of the rest (and fully morphed) positions it influences, for
  // conservative posed bounds (deformed_bounds()).
  std::vector<Aabb> joint_bounds;
  bool skinned() const { return !joints.empty(); }
};

// On a deformable mesh's entity: the joints' entities (their Transform::world drives the pose) and the
// glTF inverse bind matrices, one per joint.
struct Skeleton {
  std::vector<Entity> joints;
  std::vector<glm::mat4> inverse_bind;
};

// On a mesh entity with morph targets: the current weights, one per target (initialised from
// DeformData::default_weights, written by animation).
struct MorphWeights {
  std::vector<float> weights;
};

// A keyframe animation (glTF animations): each channel drives one entity's translation, rotation,
// scale or morph weights.
struct AnimationClip {
  enum class Path : uint32_t { Translation, Rotation, Scale, Weights };
  enum class Interpolation : uint32_t { Linear, Step, CubicSpline };
  struct Channel {
    Entity target;
    Path path = Path::Translation;
    Interpolation interpolation = Interpolation::Linear;
    std::vector<float> times;   // seconds, increasing
    // Per key: 3 (translation, scale), 4 (rotation quaternion x, y, z, w) or the target count
    // (weights) floats; CubicSpline keys hold in-tangent, value, out-tangent.
    std::vector<float> values;
    uint32_t components = 3;
  };
  std::string name;
  std::vector<Channel> channels;
  float duration = 0.0f;  // the last key time over all channels
};

// Plays a clip on the entities its channels name, looping: at time t the pose is the clip's at
// fmod(t * speed + phase, duration).
struct AnimationPlayer {
  std::shared_ptr<const AnimationClip> clip;
  float speed = 1.0f;
  float phase = 0.0f;  // seconds
  bool playing = true;
};

// Poses every AnimationPlayer's targets for absolute time `seconds` (deterministic: same time, same
// pose). Runs before update_world_transforms.
void update_clip_animations(Registry& registry, float seconds);

// The skinning matrices of a deformable entity for the current pose, in its object space:
// inverse(entity world) * joint world * inverse bind, one per joint. Empty for an entity without a
// Skeleton. Reads Transform::world (after update_world_transforms).
std::vector<glm::mat4> joint_matrices(const Registry& registry, Entity entity);

// The deformed vertices of `mesh` (positions and normals in object space; uvs as rest) for these morph
// weights (empty: none) and joint matrices (empty: no skinning). Exactly skinning.comp's arithmetic in
// float, so the reference and the GPU agree to rounding.
void deform_vertices(const MeshData& mesh, std::span<const float> morph_weights,
                     std::span<const glm::mat4> joint_matrices, std::vector<Vertex>& out);

// A box in object space holding every deformed position for this pose (conservative, from
// DeformData::joint_bounds and the morph weights; no per-vertex work).
Aabb deformed_bounds(const MeshData& mesh, std::span<const float> morph_weights,
                     std::span<const glm::mat4> joint_matrices);

// The deformed vertices of a mesh entity in its current pose (its MorphWeights and Skeleton), or its
// rest vertices when it has no DeformData: what the reference traces.
std::vector<Vertex> posed_vertices(const Registry& registry, Entity entity);

}  // namespace engine
