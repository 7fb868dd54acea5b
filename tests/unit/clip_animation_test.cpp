// Keyframe clips (engine/core/skinning.hpp): sampling by interpolation, looping, and the CPU
// deformation the reference traces.
#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"

namespace {

using namespace engine;

struct ClipFixture : testing::Test {
  Registry r;
  Entity target = r.create();
  Entity player = r.create();
  void SetUp() override { r.emplace<Transform>(target); }
  void play(AnimationClip::Channel c) {
    c.target = target;
    auto clip = std::make_shared<AnimationClip>();
    clip->duration = c.times.back();
    clip->channels.push_back(std::move(c));
    r.emplace<AnimationPlayer>(player, AnimationPlayer{std::move(clip)});
  }
};

TEST_F(ClipFixture, LinearStepAndCubicTranslationsAndLooping) {
  AnimationClip::Channel c;
  c.path = AnimationClip::Path::Translation;
  c.times = {0.0f, 1.0f, 2.0f};
  c.values = {0, 0, 0, 2, 4, 6, 0, 0, 0};
  play(c);
  update_clip_animations(r, 0.5f);
  EXPECT_EQ(r.get<Transform>(target).translation, glm::vec3(1, 2, 3));
  update_clip_animations(r, 2.5f);  // loops: 0.5 s into the clip again
  EXPECT_EQ(r.get<Transform>(target).translation, glm::vec3(1, 2, 3));
  r.get<AnimationPlayer>(player).clip = nullptr;
  c.interpolation = AnimationClip::Interpolation::Step;
  play(c);
  update_clip_animations(r, 0.9f);
  EXPECT_EQ(r.get<Transform>(target).translation, glm::vec3(0, 0, 0));
  // Cubic spline: in-tangent, value, out-tangent per key; zero tangents give smoothstep.
  c.interpolation = AnimationClip::Interpolation::CubicSpline;
  c.times = {0.0f, 1.0f};
  c.values = {0, 0, 0, 0, 0, 0, 0, 0, 0, /**/ 0, 0, 0, 4, 4, 4, 0, 0, 0};
  play(c);
  update_clip_animations(r, 0.5f);
  EXPECT_NEAR(r.get<Transform>(target).translation.x, 2.0f, 1e-6f);
  update_clip_animations(r, 0.25f);
  EXPECT_NEAR(r.get<Transform>(target).translation.x, 4.0f * (3 * 0.0625f - 2 * 0.015625f), 1e-6f);
}

TEST_F(ClipFixture, RotationsSlerpAndWeightsReachMorphWeights) {
  AnimationClip::Channel c;
  c.path = AnimationClip::Path::Rotation;
  c.components = 4;
  c.times = {0.0f, 1.0f};
  const glm::quat q = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 0, 1));
  c.values = {0, 0, 0, 1, q.x, q.y, q.z, q.w};
  play(c);
  update_clip_animations(r, 0.5f);
  const glm::quat half = r.get<Transform>(target).rotation;
  EXPECT_NEAR(glm::degrees(glm::angle(half)), 45.0f, 1e-3f);
  r.emplace<MorphWeights>(target, MorphWeights{{0.0f, 0.0f}});
  AnimationClip::Channel w;
  w.path = AnimationClip::Path::Weights;
  w.components = 2;
  w.times = {0.0f, 2.0f};
  w.values = {0, 1, 1, 0};
  play(w);
  update_clip_animations(r, 0.5f);
  EXPECT_EQ(r.get<MorphWeights>(target).weights, (std::vector<float>{0.25f, 0.75f}));
}

// A two-joint skin that bends: the rest pose gives the rest vertices back, a bent pose moves only what
// the moving joint weighs, and deformed_bounds holds every deformed position.
TEST(Skinning, RestPoseIsIdentityAndBoundsHoldEveryPosedVertex) {
  Registry r;
  const Entity mesh_entity = r.create(), root = r.create(), tip = r.create();
  r.emplace<Transform>(mesh_entity, Transform{glm::vec3(3, 0, 1)});
  r.emplace<Transform>(root, Transform{glm::vec3(3, 0, 1)});
  Transform t{glm::vec3(0, 1, 0)};
  t.parent = root;
  r.emplace<Transform>(tip, t);
  auto data = std::make_shared<MeshData>();
  auto deform = std::make_shared<DeformData>();
  for (int i = 0; i <= 20; ++i) {
    const float y = 0.1f * float(i);
    for (float x : {-0.1f, 0.1f}) {
      data->vertices.push_back({glm::vec3(x, y, 0.0f), glm::vec3(0, 0, 1), glm::vec2(0)});
      const float w = glm::clamp(y - 0.5f, 0.0f, 1.0f);
      deform->joints.push_back(glm::uvec4(0, 1, 0, 0));
      deform->weights.push_back(glm::vec4(1.0f - w, w, 0, 0));
    }
  }
  for (uint32_t i = 0; i + 3 < uint32_t(data->vertices.size()); i += 2) data->indices.insert(data->indices.end(), {i, i + 1, i + 2});
  deform->joint_count = 2;
  deform->joint_bounds.assign(2, Aabb{});
  for (size_t v = 0; v < data->vertices.size(); ++v)
    for (int k = 0; k < 2; ++k)
      if (deform->weights[v][k] > 0.0f) deform->joint_bounds[size_t(k)].extend(data->vertices[v].position);
  data->compute_bounds();
  data->deform = deform;
  r.emplace<Mesh>(mesh_entity, Mesh{data});
  update_world_transforms(r);
  // glTF's inverse bind matrices take the mesh's rest vertices into each joint's space.
  const glm::mat4 mesh_world = r.get<Transform>(mesh_entity).world;
  r.emplace<Skeleton>(mesh_entity, Skeleton{{root, tip}, {glm::inverse(r.get<Transform>(root).world) * mesh_world,
                                                           glm::inverse(r.get<Transform>(tip).world) * mesh_world}});
  const auto rest = posed_vertices(r, mesh_entity);
  for (size_t v = 0; v < rest.size(); ++v)
    EXPECT_LT(glm::distance(rest[v].position, data->vertices[v].position), 1e-5f) << v;
  r.get<Transform>(tip).rotation = glm::angleAxis(glm::radians(60.0f), glm::vec3(0, 0, 1));
  update_world_transforms(r);
  const auto bent = posed_vertices(r, mesh_entity);
  EXPECT_LT(glm::distance(bent[0].position, data->vertices[0].position), 1e-5f);  // weighs the root alone
  EXPECT_GT(glm::distance(bent.back().position, data->vertices.back().position), 0.5f);
  const Aabb box = deformed_bounds(*data, {}, joint_matrices(r, mesh_entity));
  for (const Vertex& v : bent)
    EXPECT_TRUE(glm::all(glm::lessThanEqual(box.min, v.position)) && glm::all(glm::lessThanEqual(v.position, box.max)));
}

TEST(Skinning, MorphTargetsAddTheirWeightedDeltas) {
  MeshData mesh;
  mesh.vertices = {{glm::vec3(0), glm::vec3(0, 1, 0), glm::vec2(0)}, {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec2(0)}};
  auto deform = std::make_shared<DeformData>();
  deform->morph_targets.push_back({"up", {glm::vec3(0, 1, 0), glm::vec3(0, 2, 0)}, {}});
  deform->morph_targets.push_back({"side", {glm::vec3(1, 0, 0), glm::vec3(0, 0, 0)}, {}});
  mesh.deform = deform;
  mesh.compute_bounds();
  std::vector<Vertex> out;
  const std::vector<float> weights = {0.5f, 1.0f};
  deform_vertices(mesh, weights, {}, out);
  EXPECT_EQ(out[0].position, glm::vec3(1.0f, 0.5f, 0.0f));
  EXPECT_EQ(out[1].position, glm::vec3(1.0f, 1.0f, 0.0f));
  const Aabb box = deformed_bounds(mesh, weights, {});
  for (const Vertex& v : out)
    EXPECT_TRUE(glm::all(glm::lessThanEqual(box.min, v.position)) && glm::all(glm::lessThanEqual(v.position, box.max)));
}

}  // namespace
