// The walkthrough's CPU parts: collision, the player's movement, input scripts, scene files and the
// animation system. No GPU.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "collision.hpp"
#include "dynamic_resolution.hpp"
#include "engine/assets/procedural_scenes.hpp"
#include "engine/assets/scene_file.hpp"
#include "engine/core/animation.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"
#include "input.hpp"
#include "player.hpp"

namespace {

using namespace walkthrough;
const std::string kContent = std::string(ENGINE_SOURCE_DIR) + "/content/";

// A floor at y = 0 and a wall whose near face is at z = -5.
CollisionWorld floor_and_wall() {
  CollisionWorld w;
  w.add_mesh(engine::procedural::make_ground(20, 20, 0.0f, 2), glm::mat4(1.0f));
  w.add_mesh(engine::procedural::make_box({10, 2, 0.2f}, {0, 2, -5.2f}), glm::mat4(1.0f));
  w.build();
  return w;
}

InputFrame frame(uint32_t keys, float dx = 0.0f, float dt = 0.05f) { return InputFrame{dt, keys, dx, 0.0f}; }

TEST(Collision, SpherePushedOutOfWallAndFloor) {
  const auto w = floor_and_wall();
  glm::vec3 c{0.0f, 0.2f, -4.9f};  // into the floor and the wall
  const auto contacts = w.resolve_sphere(c, 0.3f);
  EXPECT_FALSE(contacts.empty());
  EXPECT_NEAR(c.y, 0.3f, 1e-3f);
  EXPECT_NEAR(c.z, -4.7f, 1e-3f);
  EXPECT_TRUE(w.segment_blocked({0, 1, 0}, {0, 1, -10}));
  EXPECT_FALSE(w.segment_blocked({0, 1, 0}, {0, 1, 4}));
  EXPECT_NEAR(w.ray_down({0, 3, 0}, 10.0f), 3.0f, 1e-4f);
}

TEST(Player, WalksTurnsAndStopsAtWall) {
  const auto w = floor_and_wall();
  Player p(&w, {0, 1.6f, 5}, {0, 1.6f, 0});
  EXPECT_FALSE(p.flying());
  EXPECT_NEAR(p.feet().y, 0.0f, 0.02f);
  for (int i = 0; i < 20; ++i) p.update(frame(kKeyForward));  // 1 s at 4 m/s
  EXPECT_NEAR(p.feet().z, 1.0f, 0.05f);
  for (int i = 0; i < 10; ++i) p.update(frame(0, 62.8319f));  // 90 degrees right
  EXPECT_NEAR(p.forward().x, 1.0f, 1e-3f);
  for (int i = 0; i < 10; ++i) p.update(frame(0, -62.8319f));
  for (int i = 0; i < 200; ++i) p.update(frame(kKeyForward | kKeySprint));  // 10 s into the wall
  EXPECT_NEAR(p.feet().z, -4.7f, 0.02f);
  EXPECT_NEAR(p.feet().y, 0.0f, 0.02f);
  EXPECT_TRUE(p.grounded());
}

TEST(Player, GravityJumpAndFly) {
  const auto w = floor_and_wall();
  Player p(&w, {0, 1.6f, 5}, {0, 1.6f, 0});
  p.update(frame(kKeyJump));
  float peak = 0.0f;
  for (int i = 0; i < 40; ++i) {
    p.update(frame(kKeyJump));  // held: only the press jumps
    peak = std::max(peak, p.feet().y);
  }
  EXPECT_GT(peak, 0.6f);
  EXPECT_NEAR(p.feet().y, 0.0f, 0.02f);  // landed, not through the floor
  p.update(frame(kKeyFly));
  EXPECT_TRUE(p.flying());
  for (int i = 0; i < 20; ++i) p.update(frame(kKeyJump));
  EXPECT_GT(p.feet().y, 4.0f);  // flies up, no gravity
  for (int i = 0; i < 200; ++i) p.update(frame(kKeyDown));
  EXPECT_NEAR(p.feet().y, 0.0f, 0.02f);  // flying still collides with the floor
}

TEST(InputScript, RoundTripsAndRejectsBadLines) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto path = dir / "walkthrough_input_test.input";
  std::vector<InputFrame> frames = {frame(kKeyForward | kKeySprint), frame(kKeyForward | kKeySprint),
                                    frame(0, 12.5f), frame(kKeyFly | kKeyJump)};
  save_input_script(path, frames);
  const auto back = load_input_script(path);
  ASSERT_EQ(back.size(), frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(back[i].keys, frames[i].keys);
    EXPECT_FLOAT_EQ(back[i].mouse_dx, frames[i].mouse_dx);
    EXPECT_FLOAT_EQ(back[i].dt, frames[i].dt);
  }
  std::ofstream(path) << "0.1 W 0 0\n0.1 W nan 0\n";
  try {
    load_input_script(path);
    FAIL() << "accepted a bad line";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("walkthrough_input_test.input:2: MOUSE_DX"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(SceneFile, CourtyardLoadsWithAnimatedCastersAndFlags) {
  auto scene = engine::load_scene_file(kContent + "levels/courtyard.json");
  EXPECT_EQ(scene->name, "courtyard");
  EXPECT_GE(scene->views.size(), 3u);
  ASSERT_TRUE(scene->start.has_value());
  EXPECT_GE(scene->registry.count<engine::Animated>(), 3u);  // lamp, fan, walker
  int csm_on = 0, non_casters = 0;
  scene->registry.each<engine::ShadowCaster>([&](engine::Entity, engine::ShadowCaster& c) {
    csm_on += c.csm == engine::CsmChoice::On;
    non_casters += !c.casts_shadow;
  });
  EXPECT_GE(csm_on, 1);
  EXPECT_GE(non_casters, 1);
  // The tour never passes through geometry: every leg of the authored tour is a straight flight.
  CollisionWorld w = CollisionWorld::from_scene(*scene, [&](engine::Entity e) { return scene->registry.has<engine::Animated>(e); });
  for (size_t i = 0; i < scene->views.size(); ++i)
    EXPECT_FALSE(w.segment_blocked(scene->views[i].eye, scene->views[(i + 1) % scene->views.size()].eye)) << "leg " << i;
}

// Low detail builds the same plants coarser: every plant where it stands at full detail (the same
// bounds), a quarter of the leaf cards, one-sided; the walking character with a quarter of its slices
// (fewer triangles, the same skeleton); the rest of the level untouched.
TEST(SceneFile, LowDetailPlantsStandWhereFullOnesDoWithAQuarterOfTheLeavesOneSided) {
  auto full = engine::load_scene_file(kContent + "levels/courtyard.json");
  auto low = engine::load_scene_file(kContent + "levels/courtyard.json", engine::Detail::Low);
  auto meshes = [](engine::Scene& s) {
    std::map<std::string, std::shared_ptr<const engine::MeshData>> out;
    s.registry.each<engine::Name, engine::Mesh>([&](engine::Entity, engine::Name& n, engine::Mesh& m) { out[n.value] = m.data; });
    return out;
  };
  const auto f = meshes(*full), l = meshes(*low);
  ASSERT_EQ(f.size(), l.size());
  for (const auto& [name, mesh] : f) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(l.count(name));
    const auto& coarse = *l.at(name);
    if (name == "hedge_plants_leaves") {
      EXPECT_EQ(coarse.indices.size() * 8, mesh->indices.size());
    } else if (name == "hedge_plants_stems") {
      EXPECT_LT(coarse.indices.size(), mesh->indices.size());
    } else if (name == "walker") {
      EXPECT_LT(coarse.indices.size() * 8, mesh->indices.size());
      ASSERT_TRUE(coarse.deform && mesh->deform);
      EXPECT_EQ(coarse.deform->joint_count, mesh->deform->joint_count);
      continue;
    } else {
      EXPECT_EQ(coarse.indices, mesh->indices);
      EXPECT_EQ(coarse.vertices.size(), mesh->vertices.size());
      continue;
    }
    // Leaf cards twice the size may reach a little further out than the full ones.
    EXPECT_LT(glm::distance(coarse.bounds.min, mesh->bounds.min), 0.5f);
    EXPECT_LT(glm::distance(coarse.bounds.max, mesh->bounds.max), 0.5f);
  }
}

TEST(SceneFile, ErrorsNameFileAndField) {
  const auto path = std::filesystem::temp_directory_path() / "scene_file_test.json";
  auto expect_error = [&](const std::string& text, const std::string& message) {
    std::ofstream(path) << text;
    try {
      engine::load_scene_file(path);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const engine::SceneError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos);
      EXPECT_NE(what.find("scene_file_test.json: " + message), std::string::npos) << what;
    }
  };
  const std::string view = R"("views": [{"eye": [0, 2, 5], "target": [0, 0, 0]}])";
  expect_error("{" + view + "}", "(top level).objects: missing");
  expect_error(R"({"objects": [{"shape": {"sphere": {"radius": 1}}}]})", "(top level).views: missing");
  expect_error("{" + view + R"(, "objects": [{"shape": {"sphere": {"radius": -1}}}]})", "objects[0].shape.sphere.radius");
  expect_error("{" + view + R"(, "objects": [{"shape": {"sphere": {"radius": 1}}, "colour": [1, 0, 0]}]})",
               "objects[0].colour: unknown field");
  expect_error("{" + view + R"(, "objects": [{"shape": {"sphere": {"radius": 1}}, "gltf": "x.gltf"}]})",
               "objects[0]: needs exactly one of");
  expect_error("{" + view + R"(, "objects": [{"gltf": "missing.gltf"}]})", "objects[0].gltf:");
  std::filesystem::remove(path);
}

TEST(Animation, PosesAreDeterministicAndMove) {
  engine::Registry r;
  const auto e = r.create();
  engine::Transform t;
  t.translation = {1, 2, 3};
  r.emplace<engine::Transform>(e, t);
  engine::Animated swing;
  swing.kind = engine::Animated::Kind::Swing;
  swing.axis = {0, 0, 1};
  swing.amplitude = 0.5f;
  swing.period = 2.0f;
  engine::make_animated(r, e, swing);
  engine::update_animations(r, 0.5f);  // quarter period: full amplitude
  const glm::quat q = r.get<engine::Transform>(e).rotation;
  EXPECT_NEAR(glm::angle(q), 0.5f, 1e-4f);
  engine::update_animations(r, 0.0f);
  EXPECT_NEAR(glm::angle(r.get<engine::Transform>(e).rotation), 0.0f, 1e-3f);
  EXPECT_EQ(r.get<engine::Transform>(e).translation, glm::vec3(1, 2, 3));
}

TEST(DynamicResolution, ShrinksWhenSlowGrowsWhenFastOffWhenDisabled) {
  DynamicResolution d(10.0f);  // 100 ms target
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(d.add_frame(400.0f));
  EXPECT_TRUE(d.add_frame(400.0f));  // far over the target: acts after four frames
  EXPECT_FLOAT_EQ(d.scale(), 0.5f);  // four times too slow: half the side (at most half per step)
  for (int i = 0; i < 7; ++i) d.add_frame(150.0f);
  EXPECT_FLOAT_EQ(d.scale(), 0.5f);  // 1.5x over: waits for a full window of eight
  EXPECT_TRUE(d.add_frame(150.0f));
  EXPECT_LT(d.scale(), 0.5f);
  for (int step = 0; step < 10; ++step)
    for (int i = 0; i < 8; ++i) d.add_frame(400.0f);
  EXPECT_FLOAT_EQ(d.scale(), DynamicResolution::kMinScale);  // the floor
  for (int step = 0; step < 40; ++step)
    for (int i = 0; i < 8; ++i) d.add_frame(20.0f);
  EXPECT_FLOAT_EQ(d.scale(), 1.0f);  // back to full size when fast
  for (int i = 0; i < 8; ++i) d.add_frame(95.0f);
  EXPECT_FLOAT_EQ(d.scale(), 1.0f);  // within the band: no change
  for (int i = 0; i < 8; ++i) d.add_frame(104.0f);
  EXPECT_FLOAT_EQ(d.scale(), 0.925f);  // just over: aims a tenth under the target, sqrt(90 / 104) = 0.93
  EXPECT_FLOAT_EQ(DynamicResolution(10.0f, 0.5f).scale(), 0.5f);  // a CPU device starts at half size
  EXPECT_FLOAT_EQ(DynamicResolution(10.0f, 0.01f).scale(), DynamicResolution::kMinScale);
  // A start like lavapipe's: three frames of one-time work put the first window's median just over the
  // target, which shrinks nothing; the same median in the next window does.
  DynamicResolution start(10.0f, 0.5f);
  for (float ms : {488.0f, 95.0f, 740.0f, 101.0f, 103.0f, 751.0f, 102.0f, 73.0f}) EXPECT_FALSE(start.add_frame(ms));
  EXPECT_GT(start.median_ms(), 100.0f);
  EXPECT_FLOAT_EQ(start.scale(), 0.5f);
  for (int i = 0; i < 7; ++i) EXPECT_FALSE(start.add_frame(103.0f));
  EXPECT_TRUE(start.add_frame(103.0f));
  EXPECT_LT(start.scale(), 0.5f);
  d.enabled = false;
  EXPECT_TRUE(d.add_frame(1000.0f));  // off: full size at once, whatever the frame time
  EXPECT_FLOAT_EQ(d.scale(), 1.0f);
  EXPECT_FALSE(d.add_frame(1000.0f));
}

}  // namespace

// A level's "lights": a spot light aimed by its direction (its entity's local -Z) and a point light;
// a malformed light is refused in one line naming its field.
TEST(SceneFile, LoadsSpotAndPointLightsAndRefusesBadOnes) {
  const std::string path = (std::filesystem::temp_directory_path() / "scene_file_lights_test.json").string();
  std::ifstream in(kContent + "test_levels/wall.json");
  nlohmann::json level = nlohmann::json::parse(in);
  level["lights"] = {{{"type", "spot"}, {"name", "lamp"}, {"position", {0, 4, 0}}, {"direction", {0, -1, 0}},
                      {"range", 12}, {"inner_cone_deg", 20}, {"outer_cone_deg", 35}, {"intensity", 50}},
                     {{"type", "point"}, {"position", {3, 2, -1}}, {"range", 8}, {"color", {1, 0.8, 0.6}}}};
  std::ofstream(path) << level.dump();
  auto scene = engine::load_scene_file(path);
  ASSERT_EQ(scene->registry.count<engine::SpotLight>(), 1u);
  ASSERT_EQ(scene->registry.count<engine::PointLight>(), 1u);
  scene->registry.each<engine::SpotLight, engine::Transform>([](engine::Entity, engine::SpotLight& s, engine::Transform& t) {
    EXPECT_NEAR(glm::distance(glm::vec3(t.world[3]), glm::vec3(0, 4, 0)), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::distance(-glm::vec3(t.world[2]), glm::vec3(0, -1, 0)), 0.0f, 1e-5f);
    EXPECT_FLOAT_EQ(s.range, 12.0f);
    EXPECT_NEAR(s.outer_cone, glm::radians(35.0f), 1e-6f);
  });
  scene->registry.each<engine::PointLight, engine::Transform>([](engine::Entity, engine::PointLight& p, engine::Transform& t) {
    EXPECT_NEAR(glm::distance(glm::vec3(t.world[3]), glm::vec3(3, 2, -1)), 0.0f, 1e-5f);
    EXPECT_FLOAT_EQ(p.range, 8.0f);
  });
  const std::vector<std::pair<nlohmann::json, std::string>> bad = {
      {{{"type", "area"}, {"position", {0, 1, 0}}, {"range", 4}}, "lights[0].type"},
      {{{"type", "point"}, {"position", {0, 1, 0}}}, "lights[0].range: missing"},
      {{{"type", "spot"}, {"position", {0, 1, 0}}, {"range", 4}, {"direction", {0, 0, 0}}}, "lights[0].direction"},
      {{{"type", "spot"}, {"position", {0, 1, 0}}, {"range", 4}, {"direction", {0, -1, 0}}, {"inner_cone_deg", 50},
        {"outer_cone_deg", 40}},
       "lights[0].inner_cone_deg"},
      {{{"type", "point"}, {"position", {0, 1, 0}}, {"range", 4}, {"colour", {1, 1, 1}}}, "lights[0].colour: unknown field"},
  };
  for (const auto& [light, expected] : bad) {
    SCOPED_TRACE(expected);
    level["lights"] = nlohmann::json::array({light});
    std::ofstream(path) << level.dump();
    try {
      engine::load_scene_file(path);
      ADD_FAILURE() << "loaded";
    } catch (const engine::SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(path);
}
