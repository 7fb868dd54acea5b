#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "engine/assets/scene.hpp"
#include "engine/core/transform_system.hpp"

namespace {

using namespace engine;
namespace fs = std::filesystem;

fs::path test_file(const std::string& name) { return fs::path(ENGINE_SOURCE_DIR) / "content" / "test_gltf" / name; }

Entity find_named(Scene& scene, const std::string& name) {
  Entity found = kNullEntity;
  scene.registry.each<Name>([&](Entity e, Name& n) {
    if (n.value == name) found = e;
  });
  return found;
}

size_t mesh_entities(Scene& scene) { return scene.registry.count<Mesh>(); }

glm::vec3 project(const Camera& c, const glm::vec3& p) {
  const glm::vec4 clip = c.projection * c.view * glm::vec4(p, 1.0f);
  return glm::vec3(clip) / clip.w;
}

// Writes a .glb container: 12-byte header, JSON chunk (space padded), BIN chunk (zero padded).
void write_glb(const fs::path& path, std::string json, std::string bin) {
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const uint32_t total = 12 + 8 + uint32_t(json.size()) + (bin.empty() ? 0 : 8 + uint32_t(bin.size()));
  std::string out = "glTF" + u32(2) + u32(total);
  out += u32(uint32_t(json.size())) + "JSON" + json;
  if (!bin.empty()) out += u32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
  std::ofstream(path, std::ios::binary).write(out.data(), std::streamsize(out.size()));
}

std::string float_bytes(std::initializer_list<float> values) {
  std::string s;
  for (float v : values) s.append(reinterpret_cast<const char*>(&v), 4);
  return s;
}

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("engine_gltf_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

TEST(GltfLoader, LoadsTriangleWithHierarchyAndMaterial) {
  auto scene = load_gltf_scene(test_file("triangle.gltf"));
  EXPECT_EQ(scene->name, "triangle");
  EXPECT_EQ(scene->triangle_count(), 1u);
  EXPECT_EQ(mesh_entities(*scene), 1u);
  const Entity tri = find_named(*scene, "triangle");
  const Entity root = find_named(*scene, "root");
  ASSERT_TRUE(tri.valid());
  ASSERT_TRUE(root.valid());
  Registry& r = scene->registry;
  EXPECT_EQ(r.get<Transform>(tri).parent, root);
  ASSERT_TRUE(r.has<Mesh>(tri));
  EXPECT_TRUE(r.has<ShadowCaster>(tri));
  const Material& m = r.get<Material>(tri);
  EXPECT_FLOAT_EQ(m.base_color.r, 0.2f);
  EXPECT_FLOAT_EQ(m.base_color.b, 0.6f);
  EXPECT_EQ(m.alpha_mode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.25f);
  const MeshData& d = *r.get<Mesh>(tri).data;
  ASSERT_EQ(d.vertices.size(), 3u);
  EXPECT_EQ(d.indices, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(d.vertices[1].position, glm::vec3(1, 0, 0));
  EXPECT_EQ(d.vertices[2].normal, glm::vec3(0, 0, 1));

  // root translates by (1,2,3), the triangle node scales by 2.
  const Aabb b = scene->world_bounds();
  EXPECT_NEAR(b.min.x, 1.0f, 1e-5f);
  EXPECT_NEAR(b.min.y, 2.0f, 1e-5f);
  EXPECT_NEAR(b.max.x, 3.0f, 1e-5f);
  EXPECT_NEAR(b.max.y, 4.0f, 1e-5f);
  EXPECT_NEAR(b.max.z, 3.0f, 1e-5f);

  EXPECT_TRUE(r.has<Camera>(scene->camera));
  EXPECT_TRUE(r.has<DirectionalLight>(scene->light));
}

TEST(GltfLoader, FileWithoutCamerasGetsOverviewAndInsideViews) {
  auto scene = load_gltf_scene(test_file("triangle.gltf"));
  ASSERT_EQ(scene->views.size(), 2u);
  EXPECT_EQ(scene->views[0].name, "overview");
  EXPECT_EQ(scene->views[1].name, "inside");
  const Aabb b = scene->world_bounds();
  const SceneView& overview = scene->views[0];
  EXPECT_GT(overview.eye.y, b.max.y);
  EXPECT_NEAR(glm::distance(overview.target, b.center()), 0.0f, 1e-4f);
  const SceneView& inside = scene->views[1];
  EXPECT_NEAR(inside.eye.y, b.min.y + 0.12f * b.extent().y, 1e-4f);
  EXPECT_NEAR(inside.eye.y, inside.target.y, 1e-5f);  // looks horizontally along the long axis (x)
  EXPECT_GT(std::abs(inside.target.x - inside.eye.x), 0.0f);
  EXPECT_NEAR(inside.target.z, inside.eye.z, 1e-5f);
  for (const SceneView& v : scene->views) {
    EXPECT_LT(glm::normalize(v.light_direction).y, -0.7f);
  }
  const Camera& cam = scene->registry.get<Camera>(scene->camera);
  const float diag = glm::length(b.extent());
  EXPECT_NEAR(cam.near_plane, diag * 1e-3f, 1e-6f);
  EXPECT_NEAR(cam.far_plane, diag * 3.0f, 1e-4f);
}

TEST(GltfLoader, LoadsCamerasMatricesAndMultiplePrimitives) {
  testing::internal::CaptureStderr();
  auto scene = load_gltf_scene(test_file("camera.gltf"));
  const std::string log = testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("skipped 1 non-triangle primitive"), std::string::npos) << log;

  // The quad (2 triangles, uint8 indices) and the unindexed triangle; the POINTS primitive is dropped.
  EXPECT_EQ(scene->triangle_count(), 3u);
  EXPECT_EQ(mesh_entities(*scene), 2u);
  const Entity model = find_named(*scene, "model");
  ASSERT_TRUE(model.valid());
  EXPECT_FALSE(scene->registry.has<Mesh>(model));
  size_t children = 0;
  bool saw_blend = false;
  scene->registry.each<Transform, Mesh>([&](Entity e, Transform& t, Mesh& m) {
    EXPECT_EQ(t.parent, model);
    ++children;
    // No NORMAL attribute: flat normals from the winding, +z for both primitives.
    for (const Vertex& v : m.data->vertices) EXPECT_NEAR(v.normal.z, 1.0f, 1e-6f);
    if (scene->registry.get<Material>(e).alpha_mode == AlphaMode::Blend) saw_blend = true;
  });
  EXPECT_EQ(children, 2u);
  EXPECT_TRUE(saw_blend);
  EXPECT_NEAR(scene->registry.get<Transform>(model).translation.z, -5.0f, 1e-6f);
  const Aabb b = scene->world_bounds();
  EXPECT_NEAR(b.min.z, -6.0f, 1e-5f);
  EXPECT_NEAR(b.max.z, -5.0f, 1e-5f);

  ASSERT_EQ(scene->views.size(), 1u);
  const SceneView& v = scene->views[0];
  EXPECT_EQ(v.name, "main_cam");
  EXPECT_EQ(v.eye, glm::vec3(0, 1, 10));
  EXPECT_NEAR(v.target.x, 0.0f, 1e-5f);
  EXPECT_NEAR(v.target.y, 1.0f, 1e-5f);
  EXPECT_LT(v.target.z, 10.0f);
  EXPECT_FLOAT_EQ(v.vertical_fov, 0.8f);
}

TEST(GltfLoader, DefaultOverviewShowsTheWholeModel) {
  auto tri = load_gltf_scene(test_file("triangle.gltf"));
  tri->apply_view(0);
  update_world_transforms(tri->registry);
  update_camera(tri->registry, tri->camera, 1.0f);
  const Aabb b = tri->world_bounds();
  const Camera& cam = tri->registry.get<Camera>(tri->camera);
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 corner{(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z};
    const glm::vec3 ndc = project(cam, corner);
    EXPECT_LT(std::abs(ndc.x), 1.0f);
    EXPECT_LT(std::abs(ndc.y), 1.0f);
    EXPECT_GT(ndc.z, 0.0f);
    EXPECT_LT(ndc.z, 1.0f);
  }
}

TEST(GltfLoader, LoadsBinaryGlb) {
  TempDir dir;
  const std::string bin = float_bytes({0, 0, 0, 4, 0, 0, 0, 0, -4}) + std::string("\0\0\1\0\2\0", 6);
  const std::string json = R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],
    "nodes":[{"name":"floor_tri","mesh":0}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                 {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],
    "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
    "buffers":[{"byteLength":42}]})";
  const fs::path path = dir.path() / "floor.glb";
  write_glb(path, json, bin);
  auto scene = load_scene(path.string());
  EXPECT_EQ(scene->name, "floor");
  EXPECT_EQ(scene->triangle_count(), 1u);
  const Entity e = find_named(*scene, "floor_tri");
  ASSERT_TRUE(e.valid());
  const MeshData& d = *scene->registry.get<Mesh>(e).data;
  // (0,0,0), (4,0,0), (0,0,-4) winds counter-clockwise seen from +y, so the flat normal points up.
  for (const Vertex& v : d.vertices) EXPECT_NEAR(v.normal.y, 1.0f, 1e-6f);
  EXPECT_EQ(scene->world_bounds().max.x, 4.0f);

  // The same container with its binary chunk cut short must be rejected with the file name.
  const fs::path truncated = dir.path() / "truncated.glb";
  write_glb(truncated, json, bin.substr(0, 20));
  try {
    load_gltf_scene(truncated);
    ADD_FAILURE() << "truncated glb loaded";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("truncated.glb"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

struct BrokenCase {
  std::string file;
  std::string expected_fragment;  // part of the problem description
};

void PrintTo(const BrokenCase& c, std::ostream* os) { *os << c.file; }

class BrokenGltf : public ::testing::TestWithParam<BrokenCase> {};

TEST_P(BrokenGltf, ThrowsOneLineSceneErrorNamingTheFile) {
  const BrokenCase& c = GetParam();
  const fs::path path = test_file(c.file);
  try {
    load_gltf_scene(path);
    FAIL() << c.file << " loaded without error";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.find('\r'), std::string::npos) << what;
    EXPECT_NE(what.find(c.expected_fragment), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Files, BrokenGltf,
    ::testing::Values(BrokenCase{"does_not_exist.gltf", "file not found"}, BrokenCase{"broken_json.gltf", ""},
                      BrokenCase{"index_out_of_range.gltf", "index 5"},
                      BrokenCase{"nan_position.gltf", "non-finite"},
                      BrokenCase{"accessor_out_of_range.gltf", "reads past the end"},
                      BrokenCase{"bad_accessor_index.gltf", "accessor 7 out of range"},
                      BrokenCase{"wrong_component_type.gltf", "must be VEC3 of FLOAT"},
                      BrokenCase{"buffer_view_out_of_range.gltf", "exceeds buffer"},
                      BrokenCase{"missing_buffer.gltf", ""}),
    [](const ::testing::TestParamInfo<BrokenCase>& info) {
      std::string name = info.param.file.substr(0, info.param.file.find('.'));
      for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return name;
    });

// Hostile buffer URIs: a shell substitution stays a file name (older tinygltf releases expanded URIs
// with wordexp, which runs it), and a device file such as /dev/zero is refused, not read.
TEST(GltfLoader, HostileBufferUrisAreRefusedInOneLine) {
  TempDir dir;
  std::ifstream in(test_file("triangle.gltf"));
  const std::string triangle((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t uri = triangle.find("\"data:");
  ASSERT_NE(uri, std::string::npos);
  const size_t uri_end = triangle.find('"', uri + 1);
  const fs::path marker = dir.path() / "substitution_ran";
  for (const std::string& hostile : {"$(touch " + marker.string() + ")", "`touch " + marker.string() + "`",
                                     std::string("/dev/zero")}) {
    const fs::path file = dir.path() / "hostile.gltf";
    std::ofstream(file) << triangle.substr(0, uri + 1) << hostile << triangle.substr(uri_end);
    try {
      load_gltf_scene(file);
      ADD_FAILURE() << hostile << " loaded";
    } catch (const SceneError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("hostile.gltf"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
    EXPECT_FALSE(fs::exists(marker)) << hostile << " ran a command";
  }
}

// Hostile inputs that found defects (content/test_gltf/fuzz_regressions/README.md), kept after the
// fix: each loads or is rejected with one SceneError line naming the file; nothing else.
TEST(GltfLoader, FuzzRegressionFilesLoadOrFailInOneLine) {
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(test_file("fuzz_regressions"))) {
    if (entry.path().extension() == ".md") continue;
    ++files;
    SCOPED_TRACE(entry.path().filename().string());
    try {
      auto scene = load_gltf_scene(entry.path());
      for (size_t view = 0; view < scene->views.size(); ++view) scene->apply_view(view);
    } catch (const SceneError& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(entry.path().filename().string()), std::string::npos) << e.what();
    }
  }
  if (files == 0) GTEST_SKIP() << "no fuzz regression inputs kept yet";
}

TEST(SceneLoading, DispatchesByNameOrPath) {
  EXPECT_EQ(load_scene("contact")->name, "contact");
  EXPECT_EQ(load_scene(test_file("triangle.gltf").string())->triangle_count(), 1u);
  try {
    load_scene("nonsense");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "unknown scene 'nonsense': expected one of contact, atrium, foliage, canopy, a .gltf/.glb file or a .json scene file");
  }
  // A missing glTF path reaches the loader, so the error names the file rather than the scene list.
  try {
    load_scene("no/such/model.GLB");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("model.GLB: file not found"), std::string::npos) << e.what();
  }
}

TEST(SceneLoading, Sponza) {
  const fs::path path = fs::path(ENGINE_SOURCE_DIR "/../shared/content/sponza/sponza.gltf");
  if (!fs::exists(path)) GTEST_SKIP() << "sponza not present at " << path;
  auto scene = load_scene(path.string());
  EXPECT_EQ(scene->triangle_count(), 66454u);
  EXPECT_EQ(mesh_entities(*scene), 34u);
  ASSERT_EQ(scene->views.size(), 2u);
  const Aabb b = scene->world_bounds();
  ASSERT_TRUE(b.valid());
  // The interior eye is inside the building's bounds.
  const glm::vec3 eye = scene->views[1].eye;
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(eye[k], b.min[k]);
    EXPECT_LT(eye[k], b.max[k]);
  }
  scene->registry.each<Mesh>([](Entity, Mesh& m) {
    for (uint32_t i : m.data->indices) ASSERT_LT(i, m.data->vertices.size());
  });
}

}  // namespace

namespace {
// triangle.gltf with KHR_lights_punctual lights on new root nodes: `lights` is the extension's light
// array, `nodes` the nodes that hold them (each {"light": index, plus any node fields}).
fs::path write_with_lights(const TempDir& dir, const nlohmann::json& lights, const nlohmann::json& nodes) {
  std::ifstream in(test_file("triangle.gltf"));
  nlohmann::json doc = nlohmann::json::parse(in);
  doc["extensionsUsed"] = {"KHR_lights_punctual"};
  doc["extensions"]["KHR_lights_punctual"]["lights"] = lights;
  for (const auto& node : nodes) {
    nlohmann::json n = node;
    n["extensions"]["KHR_lights_punctual"] = {{"light", n["light"]}};
    n.erase("light");
    doc["scenes"][0]["nodes"].push_back(doc["nodes"].size());
    doc["nodes"].push_back(n);
  }
  const fs::path file = dir.path() / "lights.gltf";
  std::ofstream(file) << doc.dump(1);
  return file;
}
}  // namespace

// A spot and a point light placed by their nodes (the spot shines down its node's -Z, here turned to
// point straight down), a directional light as the sun, and a light without a range given one.
TEST(GltfLoader, LoadsPunctualLights) {
  TempDir dir;
  const nlohmann::json lights = {
      {{"type", "spot"}, {"color", {1.0, 0.5, 0.25}}, {"intensity", 40.0}, {"range", 12.0},
       {"spot", {{"innerConeAngle", 0.3}, {"outerConeAngle", 0.6}}}},
      {{"type", "point"}, {"intensity", 4.0}},
      {{"type", "directional"}, {"intensity", 2.0}}};
  // -90 degrees about x turns local -Z into world -Y.
  const double s = std::sqrt(0.5);
  const nlohmann::json nodes = {
      {{"name", "lamp"}, {"light", 0}, {"translation", {1.0, 4.0, 2.0}}, {"rotation", {-s, 0.0, 0.0, s}}},
      {{"name", "bulb"}, {"light", 1}, {"translation", {-3.0, 2.0, 0.0}}},
      {{"name", "sun"}, {"light", 2}, {"rotation", {-s, 0.0, 0.0, s}}}};
  auto scene = load_gltf_scene(write_with_lights(dir, lights, nodes));
  Registry& r = scene->registry;
  ASSERT_EQ(r.count<SpotLight>(), 1u);
  ASSERT_EQ(r.count<PointLight>(), 1u);
  r.each<SpotLight, Transform>([&](Entity, SpotLight& spot, Transform& t) {
    EXPECT_NEAR(glm::distance(glm::vec3(t.world[3]), glm::vec3(1.0f, 4.0f, 2.0f)), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::distance(-glm::vec3(t.world[2]), glm::vec3(0.0f, -1.0f, 0.0f)), 0.0f, 1e-5f);
    EXPECT_EQ(spot.color, glm::vec3(1.0f, 0.5f, 0.25f));
    EXPECT_FLOAT_EQ(spot.intensity, 40.0f);
    EXPECT_FLOAT_EQ(spot.range, 12.0f);
    EXPECT_FLOAT_EQ(spot.inner_cone, 0.3f);
    EXPECT_FLOAT_EQ(spot.outer_cone, 0.6f);
  });
  r.each<PointLight, Transform>([&](Entity, PointLight& point, Transform& t) {
    EXPECT_NEAR(glm::distance(glm::vec3(t.world[3]), glm::vec3(-3.0f, 2.0f, 0.0f)), 0.0f, 1e-5f);
    EXPECT_FLOAT_EQ(point.range, 32.0f);  // sqrt(256 * 4): no range in the file
  });
  const glm::vec3 sun = r.get<DirectionalLight>(scene->light).direction;
  EXPECT_NEAR(glm::distance(sun, glm::vec3(0.0f, -1.0f, 0.0f)), 0.0f, 1e-5f);
  for (const SceneView& v : scene->views) EXPECT_NEAR(glm::distance(v.light_direction, sun), 0.0f, 1e-5f);
}

// A file lit by its own spot and point lights and no directional light is lit by them alone: its
// default sun stays dark until asked for (enable_default_sun, shadow_bench --sun). A file with no
// light at all keeps a shining default sun.
TEST(GltfLoader, OwnLightsLeaveTheDefaultSunDark) {
  TempDir dir;
  const nlohmann::json lights = {{{"type", "spot"}, {"intensity", 40.0}, {"range", 12.0},
                                  {"spot", {{"innerConeAngle", 0.3}, {"outerConeAngle", 0.6}}}}};
  auto scene = load_gltf_scene(write_with_lights(dir, lights, nlohmann::json::array({{{"name", "lamp"}, {"light", 0}}})));
  DirectionalLight& sun = scene->registry.get<DirectionalLight>(scene->light);
  EXPECT_EQ(sun.intensity, 0.0f);
  EXPECT_TRUE(enable_default_sun(*scene));
  EXPECT_EQ(sun.intensity, DirectionalLight{}.intensity);
  EXPECT_FALSE(enable_default_sun(*scene));  // shining already
  auto plain = load_gltf_scene(test_file("triangle.gltf"));
  EXPECT_EQ(plain->registry.get<DirectionalLight>(plain->light).intensity, DirectionalLight{}.intensity);
}

// Each malformed light is refused with one line naming the file, the light and the problem.
TEST(GltfLoader, MalformedLightsAreRefusedInOneLine) {
  const nlohmann::json spot = {{"type", "spot"}, {"spot", {{"innerConeAngle", 0.3}, {"outerConeAngle", 0.6}}}};
  struct Case {
    nlohmann::json light;
    nlohmann::json light_index;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{{"type", "area"}}, 0, "light 0 has type \"area\""},
      {{{"type", "point"}, {"range", -1.0}}, 0, "light 0 range must be finite and >= 0"},
      {{{"type", "point"}, {"intensity", -2.0}}, 0, "light 0 intensity must be finite and >= 0"},
      {{{"type", "point"}, {"color", {1.0, 1.0}}}, 0, "light 0 color must be 3 finite numbers"},
      {{{"type", "spot"}, {"spot", {{"innerConeAngle", 0.6}, {"outerConeAngle", 0.3}}}}, 0, "light 0 cones"},
      {{{"type", "spot"}, {"spot", {{"innerConeAngle", 0.1}, {"outerConeAngle", 2.0}}}}, 0, "light 0 cones"},
      {spot, 3, "light 3 out of range (1 lights)"},
      {spot, "first", "\"light\" must be a light index"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.expected);
    TempDir dir;
    try {
      load_gltf_scene(write_with_lights(dir, nlohmann::json::array({c.light}),
                                        nlohmann::json::array({{{"name", "lamp"}, {"light", c.light_index}}})));
      ADD_FAILURE() << "loaded";
    } catch (const SceneError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("lights.gltf"), std::string::npos) << what;
      EXPECT_NE(what.find(c.expected), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}
