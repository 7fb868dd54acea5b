#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "engine/assets/procedural_scenes.hpp"
#include "engine/assets/scene.hpp"
#include "engine/core/transform_system.hpp"

namespace {

using namespace engine;

struct Triangle {
  glm::vec3 a, b, c;
};

std::vector<Triangle> world_triangles(Scene& scene) {
  update_world_transforms(scene.registry);
  std::vector<Triangle> out;
  scene.registry.each<Transform, Mesh>([&](Entity, Transform& t, Mesh& m) {
    const MeshData& d = *m.data;
    for (size_t i = 0; i + 2 < d.indices.size(); i += 3) {
      auto p = [&](size_t k) { return glm::vec3(t.world * glm::vec4(d.vertices[d.indices[i + k]].position, 1.0f)); };
      out.push_back({p(0), p(1), p(2)});
    }
  });
  return out;
}

// Moller-Trumbore; returns the ray parameter of a hit in (t_min, t_max).
std::optional<float> intersect(const Triangle& tri, const glm::vec3& o, const glm::vec3& d, float t_min, float t_max) {
  const glm::vec3 e1 = tri.b - tri.a, e2 = tri.c - tri.a;
  const glm::vec3 p = glm::cross(d, e2);
  const float det = glm::dot(e1, p);
  if (std::abs(det) < 1e-12f) return std::nullopt;
  const float inv = 1.0f / det;
  const glm::vec3 s = o - tri.a;
  const float u = glm::dot(s, p) * inv;
  if (u < 0.0f || u > 1.0f) return std::nullopt;
  const glm::vec3 q = glm::cross(s, e1);
  const float v = glm::dot(d, q) * inv;
  if (v < 0.0f || u + v > 1.0f) return std::nullopt;
  const float t = glm::dot(e2, q) * inv;
  if (t <= t_min || t >= t_max) return std::nullopt;
  return t;
}

bool occluded(const std::vector<Triangle>& tris, const glm::vec3& from, const glm::vec3& to) {
  const glm::vec3 d = to - from;
  for (const Triangle& t : tris) {
    if (intersect(t, from, d, 1e-4f, 1.0f - 1e-4f)) return true;
  }
  return false;
}

// Is the point lit by the sun? Shoots a ray from just above the point against the light direction.
bool sunlit(const std::vector<Triangle>& tris, const glm::vec3& point, const glm::vec3& light_dir) {
  const glm::vec3 start = point + glm::vec3(0, 1e-3f, 0);
  return !occluded(tris, start, start - glm::normalize(light_dir) * 100.0f);
}

Entity find_named(Scene& scene, const std::string& name) {
  Entity found = kNullEntity;
  scene.registry.each<Name>([&](Entity e, Name& n) {
    if (n.value == name) found = e;
  });
  return found;
}

double average_world_area(Scene& scene) {
  const auto tris = world_triangles(scene);
  double sum = 0.0;
  for (const Triangle& t : tris) sum += 0.5 * glm::length(glm::cross(t.b - t.a, t.c - t.a));
  return tris.empty() ? 0.0 : sum / double(tris.size());
}

glm::vec3 project(const Camera& c, const glm::vec3& p) {
  const glm::vec4 clip = c.projection * c.view * glm::vec4(p, 1.0f);
  return glm::vec3(clip) / clip.w;
}

TEST(ProceduralScenes, NamesAreTheFiveScenes) {
  EXPECT_EQ(procedural_scene_names(), (std::vector<std::string>{"contact", "atrium", "foliage", "canopy", "lamps", "hall", "characters"}));
  EXPECT_THROW(build_procedural_scene("nope"), SceneError);
}

class EveryScene : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryScene, HasCameraLightViewsAndCompleteMeshEntities) {
  auto scene = build_procedural_scene(GetParam());
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->name, GetParam());
  Registry& r = scene->registry;
  ASSERT_TRUE(r.has<Transform>(scene->camera));
  ASSERT_TRUE(r.has<Camera>(scene->camera));
  ASSERT_TRUE(r.has<DirectionalLight>(scene->light));
  ASSERT_GE(scene->views.size(), 2u);

  size_t meshes = 0;
  r.each<Mesh>([&](Entity e, Mesh& m) {
    ++meshes;
    ASSERT_TRUE(m.data);
    EXPECT_TRUE(r.has<Name>(e));
    EXPECT_TRUE(r.has<Transform>(e));
    EXPECT_TRUE(r.has<Material>(e));
    ASSERT_TRUE(r.has<ShadowCaster>(e));
    EXPECT_EQ(r.get<ShadowCaster>(e).csm, CsmChoice::Auto);
    EXPECT_GT(m.data->triangle_count(), 0u);
  });
  EXPECT_GE(meshes, 3u);

  for (size_t i = 0; i < scene->views.size(); ++i) {
    scene->apply_view(i);
    update_world_transforms(r);
    update_camera(r, scene->camera, 1.0f);
    const SceneView& v = scene->views[i];
    EXPECT_FALSE(v.name.empty());
    const glm::vec3 dir = r.get<DirectionalLight>(scene->light).direction;
    EXPECT_NEAR(glm::length(dir), 1.0f, 1e-5f);
    EXPECT_LT(dir.y, -0.3f) << "sun should come from above in view " << v.name;
    const glm::vec3 ndc = project(r.get<Camera>(scene->camera), v.target);
    EXPECT_NEAR(ndc.x, 0.0f, 1e-3f);
    EXPECT_NEAR(ndc.y, 0.0f, 1e-3f);
    EXPECT_FLOAT_EQ(r.get<Camera>(scene->camera).vertical_fov, v.vertical_fov);
  }
  EXPECT_THROW(scene->apply_view(scene->views.size()), SceneError);
}

TEST_P(EveryScene, GeometryIsFiniteIndexedInRangeAndWellFormed) {
  auto scene = build_procedural_scene(GetParam());
  scene->registry.each<Mesh>([&](Entity, Mesh& m) {
    const MeshData& d = *m.data;
    ASSERT_EQ(d.indices.size() % 3, 0u) << d.name;
    for (uint32_t i : d.indices) ASSERT_LT(i, d.vertices.size()) << d.name;
    for (const Vertex& v : d.vertices) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(std::isfinite(v.position[k]) && std::isfinite(v.normal[k])) << d.name;
        ASSERT_TRUE(v.position[k] >= d.bounds.min[k] && v.position[k] <= d.bounds.max[k]) << d.name;
      }
      ASSERT_NEAR(glm::length(v.normal), 1.0f, 1e-3f) << d.name;
    }
    // The winding must agree with the shading normals (counter-clockwise front faces).
    for (size_t t = 0; t < d.indices.size(); t += 3) {
      const Vertex &a = d.vertices[d.indices[t]], &b = d.vertices[d.indices[t + 1]], &c = d.vertices[d.indices[t + 2]];
      const glm::vec3 n = glm::cross(b.position - a.position, c.position - a.position);
      ASSERT_GT(glm::length(n), 0.0f) << d.name << " has a degenerate triangle";
      ASSERT_GT(glm::dot(n, a.normal + b.normal + c.normal), 0.0f) << d.name << " triangle " << t / 3;
    }
  });
}

TEST_P(EveryScene, IsDeterministic) {
  auto a = build_procedural_scene(GetParam());
  auto b = build_procedural_scene(GetParam());
  EXPECT_EQ(a->triangle_count(), b->triangle_count());
  const Aabb ba = a->world_bounds(), bb = b->world_bounds();
  EXPECT_EQ(ba.min, bb.min);
  EXPECT_EQ(ba.max, bb.max);
}

INSTANTIATE_TEST_SUITE_P(Procedural, EveryScene, ::testing::Values("contact", "atrium", "foliage", "lamps", "hall", "characters"));

TEST(ProceduralScenes, TriangleBudgetsAndSizesMatchTheirPurpose) {
  auto atrium = build_procedural_scene("atrium");
  auto foliage = build_procedural_scene("foliage");
  auto contact = build_procedural_scene("contact");
  const size_t atrium_tris = atrium->triangle_count();
  const size_t foliage_tris = foliage->triangle_count();
  EXPECT_GT(atrium_tris, 100u);
  EXPECT_LT(atrium_tris, 3000u);
  EXPECT_GT(foliage_tris, 20000u);
  EXPECT_LE(foliage_tris, 60000u);
  EXPECT_GT(foliage_tris, 10 * atrium_tris);
  EXPECT_LT(contact->triangle_count(), 5000u);
  const double atrium_area = average_world_area(*atrium);
  const double foliage_area = average_world_area(*foliage);
  EXPECT_GT(atrium_area, 50.0 * foliage_area);
  EXPECT_LT(foliage_area, 0.1);

  // Leaf cards come in groups of four triangles (two per side), several thousand of them.
  size_t leaf_tris = 0;
  int leaf_entities = 0;
  foliage->registry.each<Name, Mesh>([&](Entity, Name& n, Mesh& m) {
    if (n.value.rfind("leaves_", 0) == 0) {
      ++leaf_entities;
      leaf_tris += m.data->triangle_count();
    }
  });
  EXPECT_EQ(leaf_entities, procedural::foliage::kPlantCount);
  EXPECT_EQ(leaf_tris % 4, 0u);
  EXPECT_GT(leaf_tris / 4, 3000u);
  EXPECT_TRUE(find_named(*foliage, "ground").valid());
  EXPECT_TRUE(find_named(*foliage, "branches_03").valid());
  EXPECT_TRUE(find_named(*foliage, "leaves_03").valid());
}

TEST(ContactScene, LayoutMatchesTheSharedConstants) {
  namespace c = procedural::contact;
  auto scene = build_procedural_scene("contact");
  const Aabb all = scene->world_bounds();
  EXPECT_NEAR(all.min.x, -c::kGroundHalfSize, 1e-4f);
  EXPECT_NEAR(all.max.z, c::kGroundHalfSize, 1e-4f);
  EXPECT_NEAR(all.min.y, 0.0f, 1e-5f);

  auto bounds_of = [&](const std::string& name) {
    const Entity e = find_named(*scene, name);
    EXPECT_TRUE(e.valid()) << name;
    return scene->registry.get<Mesh>(e).data->bounds.transformed(scene->registry.get<Transform>(e).world);
  };
  const Aabb box = bounds_of("box");
  EXPECT_NEAR(box.max.y, 2.0f, 1e-5f);
  EXPECT_NEAR(box.min.y, 0.0f, 1e-5f);
  EXPECT_NEAR(box.max.x, c::kBoxCenter.x + c::kBoxHalfSize, 1e-5f);
  const Aabb plate = bounds_of("plate");
  EXPECT_NEAR(plate.min.y, c::kPlateCenter.y - c::kPlateHalfExtent.y, 1e-5f);
  EXPECT_NEAR(plate.max.x, c::kPlateCenter.x + c::kPlateHalfExtent.x, 1e-5f);
  const Aabb pole = bounds_of("pole");
  EXPECT_NEAR(pole.max.y, c::kPoleHeight, 1e-5f);
  EXPECT_NEAR(pole.center().x, c::kPoleBase.x, 1e-4f);
  EXPECT_LE(pole.extent().x, 2.0f * c::kPoleRadius + 1e-5f);
  const Aabb sphere = bounds_of("sphere");
  EXPECT_NEAR(sphere.max.y, c::kSphereCenter.y + c::kSphereRadius, 1e-4f);
  EXPECT_NEAR(sphere.min.y, 0.0f, 1e-4f);
}

TEST(ContactScene, FrontViewSeesPlateShadowOpenGroundAndBoxTop) {
  namespace c = procedural::contact;
  auto scene = build_procedural_scene("contact");
  scene->apply_view(0);
  update_world_transforms(scene->registry);
  update_camera(scene->registry, scene->camera, 1.0f);
  const Camera& cam = scene->registry.get<Camera>(scene->camera);
  const SceneView& view = scene->views[0];
  const auto tris = world_triangles(*scene);

  const glm::vec3 light = glm::normalize(view.light_direction);
  // Where the plate's center shadow falls on the ground.
  const glm::vec3 shadow = c::kPlateCenter + light * (c::kPlateCenter.y / -light.y);
  const glm::vec3 points[] = {shadow, glm::vec3(2.0f, 0.0f, 5.0f), c::kBoxCenter + glm::vec3(0.0f, 1.0f, 0.0f)};
  for (const glm::vec3& p : points) {
    const glm::vec3 ndc = project(cam, p);
    EXPECT_LT(std::abs(ndc.x), 0.95f) << p.x << "," << p.y << "," << p.z;
    EXPECT_LT(std::abs(ndc.y), 0.95f) << p.x << "," << p.y << "," << p.z;
    EXPECT_FALSE(occluded(tris, view.eye, p + glm::vec3(0, 1e-3f, 0))) << p.x << "," << p.y << "," << p.z;
  }
  EXPECT_FALSE(sunlit(tris, shadow, light));
  EXPECT_TRUE(sunlit(tris, glm::vec3(2.0f, 0.0f, 5.0f), light));
  EXPECT_TRUE(sunlit(tris, c::kBoxCenter + glm::vec3(0.0f, 1.0f, 0.0f), light));
}

TEST(AtriumScene, SunReachesTheFloorInPatchesOnly) {
  namespace a = procedural::atrium;
  auto scene = build_procedural_scene("atrium");
  const auto tris = world_triangles(*scene);
  const glm::vec3 light = glm::normalize(scene->views[0].light_direction);
  // Below the middle of an opening, shifted by the sun's slant from roof height to the floor.
  const float opening_mid_z = 0.5f * (a::kOpeningInnerZ + a::kOpeningOuterZ);
  const glm::vec3 shift = light * (a::kWallHeight / -light.y);
  const glm::vec3 lit = glm::vec3(0.0f, a::kWallHeight, opening_mid_z) + shift;
  EXPECT_TRUE(sunlit(tris, glm::vec3(lit.x, 0.0f, lit.z), light));
  EXPECT_TRUE(sunlit(tris, glm::vec3(lit.x, 0.0f, -lit.z + 2.0f * shift.z), light));

  // Sample the floor on a grid: a minority of it is in sun, most in shadow.
  int sunny = 0, total = 0;
  for (float x = -7.5f; x <= 7.5f; x += 1.0f) {
    for (float z = -7.5f; z <= 7.5f; z += 1.0f) {
      ++total;
      if (sunlit(tris, glm::vec3(x, 0.0f, z), light)) ++sunny;
    }
  }
  EXPECT_GT(sunny, total / 20);
  EXPECT_LT(sunny, total / 3);
  // Under the gallery roof it is always shaded.
  EXPECT_FALSE(sunlit(tris, glm::vec3(6.5f, 0.0f, 0.0f), light));
  EXPECT_FALSE(sunlit(tris, glm::vec3(-6.5f, 0.0f, 0.0f), light));

  // The interior view's eye is inside the courtyard at eye height.
  const SceneView& inside = scene->views[0];
  EXPECT_LT(std::abs(inside.eye.x), a::kHalfSize);
  EXPECT_LT(std::abs(inside.eye.z), a::kHalfSize);
  EXPECT_GT(inside.eye.y, 1.0f);
  EXPECT_LT(inside.eye.y, 2.5f);
  // The view from above looks through an opening: nothing blocks its line of sight to the target.
  const SceneView& above = scene->views[1];
  EXPECT_GT(above.eye.y, a::kWallHeight + a::kRoofThickness);
  EXPECT_FALSE(occluded(tris, above.eye, above.target + glm::vec3(0, 1e-3f, 0)));
}

TEST(MeshBuilders, ClosedShapesFaceOutwards) {
  const glm::vec3 center{1.0f, 2.0f, -3.0f};
  const MeshData shapes[] = {
      procedural::make_box(glm::vec3(1.0f, 0.5f, 2.0f), center),
      procedural::make_uv_sphere(center, 1.5f, 12, 7),
      procedural::make_cylinder(center - glm::vec3(0, 1, 0), center + glm::vec3(0, 1, 0), 0.5f, 9, true),
      procedural::make_cylinder(center - glm::vec3(1, 1, 0.5f), center + glm::vec3(1, 1, 0.5f), 0.3f, 6, true),
  };
  for (const MeshData& m : shapes) {
    ASSERT_GT(m.triangle_count(), 0u);
    double signed_volume = 0.0;
    for (size_t t = 0; t < m.indices.size(); t += 3) {
      const glm::vec3 a = m.vertices[m.indices[t]].position, b = m.vertices[m.indices[t + 1]].position,
                      c = m.vertices[m.indices[t + 2]].position;
      const glm::vec3 n = glm::cross(b - a, c - a);
      EXPECT_GT(glm::dot(n, (a + b + c) / 3.0f - center), 0.0f) << m.name << " triangle " << t / 3;
      signed_volume += double(glm::dot(a - center, glm::cross(b - center, c - center))) / 6.0;
    }
    EXPECT_GT(signed_volume, 0.0) << m.name;  // closed and outward-wound
  }
  const MeshData box = procedural::make_box(glm::vec3(1.0f, 0.5f, 2.0f));
  EXPECT_EQ(box.triangle_count(), 12u);
  EXPECT_EQ(box.bounds.min, glm::vec3(-1.0f, -0.5f, -2.0f));
  EXPECT_EQ(box.bounds.max, glm::vec3(1.0f, 0.5f, 2.0f));
}

TEST(MeshBuilders, GroundFacesUpAndDoubleSidedCardsHaveBothWindings) {
  const MeshData ground = procedural::make_ground(5.0f, 3.0f, 0.0f, 3);
  EXPECT_EQ(ground.triangle_count(), 18u);
  for (size_t t = 0; t < ground.indices.size(); t += 3) {
    const glm::vec3 a = ground.vertices[ground.indices[t]].position, b = ground.vertices[ground.indices[t + 1]].position,
                    c = ground.vertices[ground.indices[t + 2]].position;
    EXPECT_GT(glm::cross(b - a, c - a).y, 0.0f);
  }
  EXPECT_EQ(ground.bounds.max, glm::vec3(5.0f, 0.0f, 3.0f));

  const MeshData card = procedural::make_double_sided_quad(glm::vec3(0.0f), glm::vec3(0.1f, 0, 0), glm::vec3(0, 0.1f, 0));
  ASSERT_EQ(card.triangle_count(), 4u);
  int front = 0, back = 0;
  for (size_t t = 0; t < card.indices.size(); t += 3) {
    const Vertex &a = card.vertices[card.indices[t]], &b = card.vertices[card.indices[t + 1]],
                 &c = card.vertices[card.indices[t + 2]];
    const float z = glm::cross(b.position - a.position, c.position - a.position).z;
    (z > 0.0f ? front : back) += 1;
    EXPECT_GT(z * a.normal.z, 0.0f);
  }
  EXPECT_EQ(front, 2);
  EXPECT_EQ(back, 2);
}

}  // namespace

// Copies for scaling runs: N times the triangles, the meshes shared, each copy beside the others.
TEST(ReplicateScene, CopiesShareMeshesAndTileTheGround) {
  auto scene = engine::build_procedural_scene("atrium");
  const size_t triangles = scene->triangle_count();
  const engine::Aabb one = scene->world_bounds();
  const size_t meshes = scene->registry.count<engine::Mesh>();
  engine::replicate_scene(*scene, 5);
  EXPECT_EQ(scene->triangle_count(), 5 * triangles);
  EXPECT_EQ(scene->registry.count<engine::Mesh>(), 5 * meshes);
  std::set<const engine::MeshData*> distinct;
  scene->registry.each<engine::Mesh>([&](engine::Entity, engine::Mesh& m) { distinct.insert(m.data.get()); });
  EXPECT_LE(distinct.size(), meshes);
  const engine::Aabb all = scene->world_bounds();
  // Three columns (ceil(sqrt(5))) and two rows of copies, each a footprint plus a tenth apart.
  EXPECT_GT(all.extent().x, 2.5f * one.extent().x);
  EXPECT_GT(all.extent().z, 1.5f * one.extent().z);
  EXPECT_NEAR(all.extent().y, one.extent().y, 1e-3f);
  EXPECT_NE(scene->name.find("x5"), std::string::npos);
  EXPECT_THROW(engine::replicate_scene(*scene, 0), engine::SceneError);
}

// transform_scene scales and moves a whole scene with what is measured in its units, and refuses what
// float cannot hold in one line naming the option that asked.
TEST(TransformScene, ScalesAndMovesEverythingMeasuredInUnits) {
  auto scene = build_procedural_scene("lamps");
  const Aabb before = scene->world_bounds();
  const SceneView view = scene->views[0];
  float spot_range = 0.0f;
  scene->registry.each<SpotLight>([&](Entity, SpotLight& s) { spot_range = s.range; });
  const float near_plane = scene->registry.get<Camera>(scene->camera).near_plane;
  transform_scene(*scene, 100.0, glm::dvec3(1.0e4, 0.0, -2.0e3), "--scale/--offset");
  const Aabb after = scene->world_bounds();
  const glm::vec3 offset(1.0e4f, 0.0f, -2.0e3f);
  EXPECT_LT(glm::distance(after.min, before.min * 100.0f + offset), 1e-2f);
  EXPECT_LT(glm::distance(after.max, before.max * 100.0f + offset), 1e-2f);
  EXPECT_LT(glm::distance(scene->views[0].eye, view.eye * 100.0f + offset), 1e-2f);
  scene->registry.each<SpotLight>([&](Entity, SpotLight& s) { EXPECT_FLOAT_EQ(s.range, 100.0f * spot_range); });
  EXPECT_FLOAT_EQ(scene->registry.get<Camera>(scene->camera).near_plane, 100.0f * near_plane);
  EXPECT_EQ(scene->units_per_metre, 100.0);
  // The lights and the camera keep unit scale: their children are not stretched.
  scene->registry.each<SpotLight, Transform>([&](Entity, SpotLight&, Transform& t) {
    EXPECT_NEAR(glm::length(glm::vec3(t.world[0])), 1.0f, 1e-5f);
  });
}

TEST(TransformScene, RefusesWhatFloatCannotHoldInOneLine) {
  const double nan = std::nan("");
  const std::vector<std::pair<double, glm::dvec3>> bad = {{0.0, glm::dvec3(0.0)},  {-1.0, glm::dvec3(0.0)},
                                                          {nan, glm::dvec3(0.0)},  {1.0, glm::dvec3(nan, 0.0, 0.0)},
                                                          {1.0e30, glm::dvec3(0.0)}, {1.0, glm::dvec3(1.0e9, 0.0, 0.0)},
                                                          {1.0e-12, glm::dvec3(1.0e6, 0.0, 0.0)}};
  for (const auto& [scale, offset] : bad) {
    auto scene = build_procedural_scene("contact");
    try {
      transform_scene(*scene, scale, offset, "--scale/--offset");
      ADD_FAILURE() << "accepted scale " << scale << " offset " << offset.x;
    } catch (const SceneError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("--scale/--offset"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}
