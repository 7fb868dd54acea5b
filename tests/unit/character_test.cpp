#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "engine/assets/procedural_scenes.hpp"
#include "engine/assets/scene.hpp"
#include "engine/assets/scene_file.hpp"
#include "engine/core/animation.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"

using namespace engine;

namespace {

// The skinned mesh entity of the figure rooted at `root`.
Entity mesh_of(Registry& r, Entity root) {
  Entity found = kNullEntity;
  r.each<Skeleton, Transform>([&](Entity e, Skeleton&, Transform& t) {
    if (t.parent == root) found = e;
  });
  return found;
}

struct Figure {
  Scene scene;
  Entity root;
  Entity mesh;
};

std::unique_ptr<Figure> make_figure(const glm::vec3& at = {3.0f, 0.0f, -2.0f}, float phase = 0.0f) {
  auto f = std::make_unique<Figure>();
  f->root = procedural::add_walking_figure(f->scene, at, phase);
  f->mesh = mesh_of(f->scene.registry, f->root);
  update_world_transforms(f->scene.registry);
  return f;
}

// Posed vertices in world space.
std::vector<glm::vec3> world_positions(Registry& r, Entity mesh) {
  const glm::mat4 world = r.get<Transform>(mesh).world;
  std::vector<glm::vec3> out;
  for (const Vertex& v : posed_vertices(r, mesh)) out.push_back(glm::vec3(world * glm::vec4(v.position, 1.0f)));
  return out;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() / (std::to_string(getpid()) + "_" + name);
}

}  // namespace

TEST(Character, FigureIsADenseSkinnedHumanoid) {
  auto f = make_figure();
  Registry& r = f->scene.registry;
  ASSERT_TRUE(f->mesh.valid());
  EXPECT_EQ(r.get<Name>(f->root).value, "character");
  EXPECT_EQ(r.get<Name>(f->mesh).value, "character");
  EXPECT_TRUE(r.has<Material>(f->mesh));
  EXPECT_TRUE(r.has<ShadowCaster>(f->mesh));
  EXPECT_TRUE(r.has<AnimationPlayer>(f->root));
  const MeshData& mesh = *r.get<Mesh>(f->mesh).data;
  EXPECT_GE(mesh.triangle_count(), 10000u);
  EXPECT_NEAR(mesh.bounds.max.y - mesh.bounds.min.y, 1.75f, 0.03f);
  EXPECT_NEAR(mesh.bounds.min.y, 0.0f, 1e-4f);
  ASSERT_TRUE(mesh.deform && mesh.deform->skinned());
  const DeformData& d = *mesh.deform;
  const Skeleton& skeleton = r.get<Skeleton>(f->mesh);
  EXPECT_EQ(d.joint_count, 12u);
  EXPECT_EQ(skeleton.joints.size(), 12u);
  EXPECT_EQ(skeleton.inverse_bind.size(), 12u);
  ASSERT_EQ(d.joints.size(), mesh.vertices.size());
  ASSERT_EQ(d.weights.size(), mesh.vertices.size());
  ASSERT_EQ(d.joint_bounds.size(), 12u);
  size_t blended = 0;
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    float sum = 0.0f;
    int used = 0;
    for (int k = 0; k < 4; ++k) {
      ASSERT_GE(d.weights[v][k], 0.0f);
      if (d.weights[v][k] == 0.0f) continue;
      ++used;
      sum += d.weights[v][k];
      ASSERT_LT(d.joints[v][k], d.joint_count);
      const Aabb& b = d.joint_bounds[d.joints[v][k]];
      ASSERT_TRUE(glm::all(glm::greaterThanEqual(mesh.vertices[v].position, b.min)) &&
                  glm::all(glm::lessThanEqual(mesh.vertices[v].position, b.max)));
    }
    ASSERT_NEAR(sum, 1.0f, 1e-5f);
    ASSERT_LE(used, int(kMaxJointsPerVertex));
    blended += used > 1;
  }
  // Smooth joints: a good share of the vertices blend two joints.
  EXPECT_GT(blended, mesh.vertices.size() / 10);
  // Every joint is its own entity below the root.
  for (Entity j : skeleton.joints) {
    ASSERT_TRUE(r.has<Transform>(j));
    EXPECT_TRUE(r.get<Transform>(j).parent.valid());
  }
}

TEST(Character, RestPoseReproducesTheRestVertices) {
  auto f = make_figure();
  Registry& r = f->scene.registry;
  const MeshData& mesh = *r.get<Mesh>(f->mesh).data;
  const std::vector<Vertex> posed = posed_vertices(r, f->mesh);
  ASSERT_EQ(posed.size(), mesh.vertices.size());
  for (size_t v = 0; v < posed.size(); ++v) {
    ASSERT_NEAR(glm::length(posed[v].position - mesh.vertices[v].position), 0.0f, 1e-5f) << v;
    ASSERT_NEAR(glm::length(posed[v].normal - mesh.vertices[v].normal), 0.0f, 1e-4f) << v;
  }
}

TEST(Character, WalkClipMovesTheFeetInsideDeformedBounds) {
  auto f = make_figure();
  Registry& r = f->scene.registry;
  const MeshData& mesh = *r.get<Mesh>(f->mesh).data;
  std::vector<std::vector<glm::vec3>> poses;
  for (float t : {0.2f, 0.6f}) {
    update_clip_animations(r, t);
    update_world_transforms(r);
    const std::vector<glm::mat4> joints = joint_matrices(r, f->mesh);
    const Aabb box = deformed_bounds(mesh, {}, joints);
    for (const Vertex& v : posed_vertices(r, f->mesh)) {
      ASSERT_TRUE(glm::all(glm::greaterThanEqual(v.position, box.min)) && glm::all(glm::lessThanEqual(v.position, box.max)))
          << "t " << t;
    }
    poses.push_back(world_positions(r, f->mesh));
  }
  // The feet (the vertices below the ankles at rest) move between the two times.
  float foot_motion = 0.0f;
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if (mesh.vertices[v].position.y < 0.1f) foot_motion = std::max(foot_motion, glm::length(poses[0][v] - poses[1][v]));
  EXPECT_GT(foot_motion, 0.1f);
}

TEST(Character, CrowdHasOneFigurePerCount) {
  auto scene = procedural::build_character_crowd(4);
  Registry& r = scene->registry;
  EXPECT_EQ(r.count<Skeleton>(), 4u);
  EXPECT_EQ(r.count<AnimationPlayer>(), 4u);
  EXPECT_GE(scene->views.size(), 2u);
  // Each figure's clip drives its own joints.
  r.each<AnimationPlayer>([&](Entity root, AnimationPlayer& p) {
    ASSERT_TRUE(p.clip);
    EXPECT_NEAR(p.clip->duration, 1.1f, 1e-6f);
    for (const auto& c : p.clip->channels) {
      Entity e = c.target;
      while (r.get<Transform>(e).parent.valid() && !(r.get<Transform>(e).parent == root)) e = r.get<Transform>(e).parent;
      EXPECT_TRUE(r.get<Transform>(e).parent == root);
    }
  });
  // Phases differ, so neighbours do not step in unison.
  std::vector<float> phases;
  r.each<AnimationPlayer>([&](Entity, AnimationPlayer& p) { phases.push_back(p.phase); });
  EXPECT_NE(phases[0], phases[1]);
}

TEST(Character, LevelCharacterWalksAPath) {
  const auto path = temp_file("character_level.json");
  std::ofstream(path) << R"({"views": [{"eye": [0, 2, 6], "target": [0, 1, 0]}],
    "objects": [{"shape": {"ground": {"half_size": [10, 10]}}},
                {"name": "walker", "character": {}, "translation": [1, 0, 1],
                 "animate": {"walk": {"path": [[-3, 0, 1], [3, 0, 1], [3, 0, 5]], "speed": 1.3}}}]})";
  auto scene = load_scene_file(path);
  std::filesystem::remove(path);
  Registry& r = scene->registry;
  Entity root = kNullEntity;
  r.each<AnimationPlayer>([&](Entity e, AnimationPlayer&) { root = e; });
  ASSERT_TRUE(root.valid());
  EXPECT_EQ(r.get<Name>(root).value, "walker");
  EXPECT_TRUE(r.has<Animated>(root));
  const Entity mesh = mesh_of(r, root);
  ASSERT_TRUE(mesh.valid());
  EXPECT_EQ(r.get<Name>(mesh).value, "walker");
  update_animations(r, 1.0f);
  update_clip_animations(r, 1.0f);
  update_world_transforms(r);
  const glm::vec3 at(r.get<Transform>(root).world[3]);
  EXPECT_NEAR(at.x, -3.0f + 1.3f, 1e-3f);
  EXPECT_NEAR(at.z, 1.0f, 1e-3f);
  EXPECT_NEAR(glm::vec3(r.get<Transform>(mesh).world[3]).x, at.x, 1e-5f);
}

TEST(Character, BadCharacterFieldFailsInOneLine) {
  const auto path = temp_file("character_bad.json");
  const auto expect_error = [&](const std::string& object, const std::string& message) {
    std::ofstream(path) << R"({"views": [{"eye": [0, 2, 6], "target": [0, 1, 0]}], "objects": [)" << object << "]}";
    try {
      load_scene_file(path);
      ADD_FAILURE() << "accepted: " << object;
    } catch (const SceneError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_NE(what.find(message), std::string::npos) << what;
    }
  };
  expect_error(R"({"character": {"tessellation": 2}})", "objects[0].character.tessellation: value 2 out of range");
  expect_error(R"({"character": {"segments": 8}})", "objects[0].character.segments: unknown field");
  expect_error(R"({"character": 3})", "objects[0].character: expected an object");
  expect_error(R"({"character": {}, "shape": {"sphere": {"radius": 1}}})", "objects[0]: needs exactly one of");
  std::filesystem::remove(path);
}
