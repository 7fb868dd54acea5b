// glTF skins, morph targets and animations through engine::load_gltf_scene, with the files
// tests/support/animated_gltf.hpp writes (the same ones the GPU test renders).
#include <gtest/gtest.h>

#include <filesystem>

#include "animated_gltf.hpp"
#include "engine/assets/scene.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"

namespace {

using namespace engine;

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "skinned_gltf";
  std::filesystem::create_directories(dir);
  return dir;
}

Entity deformed_entity(Scene& scene) {
  Entity found = kNullEntity;
  scene.registry.each<Mesh>([&](Entity e, Mesh& m) {
    if (m.data && m.data->deform) found = e;
  });
  return found;
}

TEST(SkinnedGltf, BendingCylinderLoadsItsSkeletonAndPlaysItsClip) {
  auto scene = load_gltf_scene(support::write_bending_cylinder_gltf(temp_dir()));
  const Entity e = deformed_entity(*scene);
  ASSERT_TRUE(e.valid());
  const auto& skeleton = scene->registry.get<Skeleton>(e);
  EXPECT_EQ(skeleton.joints.size(), 3u);
  const DeformData& d = *scene->registry.get<Mesh>(e).data->deform;
  EXPECT_EQ(d.joint_count, 3u);
  for (const glm::vec4& w : d.weights) EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-6f);
  EXPECT_EQ(scene->registry.count<AnimationPlayer>(), 1u);
  // The bind pose gives the rest vertices back; the clip bends the top away.
  update_world_transforms(scene->registry);
  const auto rest = posed_vertices(scene->registry, e);
  const auto& vertices = scene->registry.get<Mesh>(e).data->vertices;
  float top_moved = 0.0f, rest_error = 0.0f;
  for (size_t v = 0; v < rest.size(); ++v) rest_error = std::max(rest_error, glm::distance(rest[v].position, vertices[v].position));
  EXPECT_LT(rest_error, 1e-5f);
  update_clip_animations(scene->registry, 1.0f);
  update_world_transforms(scene->registry);
  const auto bent = posed_vertices(scene->registry, e);
  const Aabb box = deformed_bounds(*scene->registry.get<Mesh>(e).data, {}, joint_matrices(scene->registry, e));
  for (size_t v = 0; v < bent.size(); ++v) {
    top_moved = std::max(top_moved, glm::distance(bent[v].position, vertices[v].position));
    EXPECT_TRUE(glm::all(glm::lessThanEqual(box.min, bent[v].position)) && glm::all(glm::lessThanEqual(bent[v].position, box.max)));
  }
  EXPECT_GT(top_moved, 0.3f);
}

TEST(SkinnedGltf, MorphTargetsAndTheirWeightsAnimate) {
  auto scene = load_gltf_scene(support::write_morph_gltf(temp_dir()));
  const Entity e = deformed_entity(*scene);
  ASSERT_TRUE(e.valid());
  EXPECT_EQ(scene->registry.get<Mesh>(e).data->deform->morph_targets.size(), 2u);
  const std::vector<float> before = scene->registry.get<MorphWeights>(e).weights;
  update_clip_animations(scene->registry, 0.5f);
  EXPECT_NE(scene->registry.get<MorphWeights>(e).weights, before);
  const auto posed = posed_vertices(scene->registry, e);
  const auto& rest = scene->registry.get<Mesh>(e).data->vertices;
  float moved = 0.0f;
  for (size_t v = 0; v < posed.size(); ++v) moved = std::max(moved, glm::distance(posed[v].position, rest[v].position));
  EXPECT_GT(moved, 0.1f);
}

TEST(SkinnedGltf, MoreThanFourWeightsAreClampedWithALine) {
  const std::string file = support::write_skinned_gltf_with_eight_weights(temp_dir());
  testing::internal::CaptureStderr();
  auto scene = load_gltf_scene(file);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("8 joint weights per vertex; kept the 4 largest"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  const Entity e = deformed_entity(*scene);
  ASSERT_TRUE(e.valid());
  for (const glm::vec4& w : scene->registry.get<Mesh>(e).data->deform->weights) {
    EXPECT_NEAR(w.x + w.y + w.z + w.w, 1.0f, 1e-6f);
    EXPECT_GE(w.x, w.y);  // the largest kept, in order
  }
}

TEST(SkinnedGltf, AJointPastTheSkinIsRefusedInOneLine) {
  const std::string file = support::write_skinned_gltf_with_bad_joint(temp_dir());
  try {
    load_gltf_scene(file);
    FAIL() << "loaded";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos);
    EXPECT_NE(what.find("joint index"), std::string::npos) << what;
    EXPECT_NE(what.find(std::filesystem::path(file).filename().string()), std::string::npos) << what;
  }
}

// Copies of a skinned scene pose their own skeletons with their own clips.
TEST(SkinnedGltf, ReplicatedCopiesPoseTheirOwnSkeletons) {
  auto scene = load_gltf_scene(support::write_bending_cylinder_gltf(temp_dir()));
  replicate_scene(*scene, 2);
  std::vector<Entity> skinned;
  scene->registry.each<Skeleton>([&](Entity e, Skeleton&) { skinned.push_back(e); });
  ASSERT_EQ(skinned.size(), 2u);
  const auto& a = scene->registry.get<Skeleton>(skinned[0]).joints;
  const auto& b = scene->registry.get<Skeleton>(skinned[1]).joints;
  for (size_t j = 0; j < a.size(); ++j) EXPECT_FALSE(a[j] == b[j]);
  EXPECT_EQ(scene->registry.count<AnimationPlayer>(), 2u);
  update_clip_animations(scene->registry, 1.0f);
  update_world_transforms(scene->registry);
  // Both bend alike (each its own copy of the clip): the same shape in object space.
  const auto pa = posed_vertices(scene->registry, skinned[0]), pb = posed_vertices(scene->registry, skinned[1]);
  for (size_t v = 0; v < pa.size(); ++v) EXPECT_LT(glm::distance(pa[v].position, pb[v].position), 1e-4f);
  EXPECT_GT(glm::distance(pa.back().position, scene->registry.get<Mesh>(skinned[0]).data->vertices.back().position), 0.05f);
}

// The committed copies (content/test_gltf, the fuzzer's seeds) load as the written files do.
TEST(SkinnedGltf, CommittedSeedsLoadWithTheirSkinsMorphsAndClips) {
  const auto dir = std::filesystem::path(ENGINE_SOURCE_DIR) / "content" / "test_gltf";
  auto skinned = load_gltf_scene(dir / "skinned_cylinder.gltf");
  EXPECT_EQ(skinned->registry.count<Skeleton>(), 1u);
  EXPECT_EQ(skinned->registry.count<AnimationPlayer>(), 1u);
  auto morph = load_gltf_scene(dir / "morph_flap.gltf");
  EXPECT_EQ(morph->registry.count<MorphWeights>(), 1u);
  EXPECT_EQ(morph->registry.count<AnimationPlayer>(), 1u);
}

}  // namespace
