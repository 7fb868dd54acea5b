#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/components.hpp"
#include "engine/core/transform_system.hpp"

namespace {

using namespace engine;

void expect_vec3_near(const glm::vec3& a, const glm::vec3& b, float tol = 1e-4f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

glm::vec3 world_position(const Transform& t) { return glm::vec3(t.world[3]); }

// Clip -> NDC for a world-space point seen by the camera.
glm::vec3 project(const Camera& c, const glm::vec3& p) {
  const glm::vec4 clip = c.projection * c.view * glm::vec4(p, 1.0f);
  return glm::vec3(clip) / clip.w;
}

Entity make_camera(Registry& r, float near_plane = 0.1f, float far_plane = 100.0f) {
  const Entity e = r.create();
  r.emplace<Transform>(e);
  Camera c;
  c.near_plane = near_plane;
  c.far_plane = far_plane;
  r.emplace<Camera>(e, c);
  return e;
}

TEST(Transform, LocalMatrixIsTranslateRotateScale) {
  Transform t;
  t.translation = {1.0f, -2.0f, 3.0f};
  t.rotation = glm::angleAxis(glm::radians(30.0f), glm::normalize(glm::vec3(1.0f, 2.0f, 0.5f)));
  t.scale = {2.0f, 0.5f, 3.0f};
  const glm::mat4 expected = glm::translate(glm::mat4(1.0f), t.translation) * glm::mat4_cast(t.rotation) *
                             glm::scale(glm::mat4(1.0f), t.scale);
  const glm::mat4 m = t.local_matrix();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(m[c][r], expected[c][r], 1e-5f) << c << "," << r;
  // Scale applies first: a point on +x lands at translation + R * (2, 0, 0).
  expect_vec3_near(glm::vec3(m * glm::vec4(1, 0, 0, 1)), t.translation + t.rotation * glm::vec3(2, 0, 0));
}

TEST(Transform, HierarchyResolvesParentsBeforeChildrenRegardlessOfCreationOrder) {
  Registry r;
  // Children created before their parents, so storage order differs from hierarchy order.
  const Entity grandchild = r.create();
  const Entity child = r.create();
  const Entity root = r.create();
  Transform tr;
  tr.translation = {10, 0, 0};
  tr.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  r.emplace<Transform>(root, tr);
  Transform tc;
  tc.translation = {0, 0, -2};  // rotated +90 deg about y: -z maps to -x
  tc.scale = glm::vec3(2.0f);
  tc.parent = root;
  r.emplace<Transform>(child, tc);
  Transform tg;
  tg.translation = {1, 0, 0};
  tg.parent = child;
  r.emplace<Transform>(grandchild, tg);

  update_world_transforms(r);
  expect_vec3_near(world_position(r.get<Transform>(root)), {10, 0, 0});
  expect_vec3_near(world_position(r.get<Transform>(child)), {8, 0, 0});
  // +x in child space: scaled by 2 and rotated to -z.
  expect_vec3_near(world_position(r.get<Transform>(grandchild)), {8, 0, -2});

  // Moving the root moves the whole chain on the next pass.
  r.get<Transform>(root).translation = {0, 5, 0};
  update_world_transforms(r);
  expect_vec3_near(world_position(r.get<Transform>(grandchild)), {-2, 5, -2});
}

TEST(Transform, CyclesAreBrokenAndEveryWorldIsFinite) {
  Registry r;
  const Entity a = r.create(), b = r.create(), c = r.create(), self = r.create();
  Transform t;
  t.translation = {1, 0, 0};
  t.parent = c;
  r.emplace<Transform>(a, t);
  t.parent = a;
  r.emplace<Transform>(b, t);
  t.parent = b;
  r.emplace<Transform>(c, t);
  t.parent = self;
  r.emplace<Transform>(self, t);

  update_world_transforms(r);
  int roots = 0;
  for (Entity e : {a, b, c}) {
    const Transform& x = r.get<Transform>(e);
    if (!x.parent.valid()) ++roots;
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(std::isfinite(x.world[3][i]));
  }
  EXPECT_EQ(roots, 1);  // exactly one link of the loop was cut
  EXPECT_FALSE(r.get<Transform>(self).parent.valid());
  // The chain that remains is consistent: positions 1, 2, 3 along x in some rotation of a, b, c.
  float sum = 0.0f;
  for (Entity e : {a, b, c}) sum += world_position(r.get<Transform>(e)).x;
  EXPECT_NEAR(sum, 6.0f, 1e-5f);
}

TEST(Transform, StaleParentIsTreatedAsRoot) {
  Registry r;
  const Entity parent = r.create();
  Transform tp;
  tp.translation = {100, 0, 0};
  r.emplace<Transform>(parent, tp);
  const Entity child = r.create();
  Transform tc;
  tc.translation = {1, 2, 3};
  tc.parent = parent;
  r.emplace<Transform>(child, tc);
  r.destroy(parent);
  const Entity reuse = r.create();  // same index, new generation: must not become the parent
  Transform tn;
  tn.translation = {-50, 0, 0};
  r.emplace<Transform>(reuse, tn);
  update_world_transforms(r);
  expect_vec3_near(world_position(r.get<Transform>(child)), {1, 2, 3});
}

TEST(Camera, PlaceCameraPutsTheTargetAtTheImageCenter) {
  Registry r;
  const Entity cam = make_camera(r);
  const glm::vec3 cases[][2] = {
      {{0, 6, 12}, {0, 0.5f, 0}},  {{5, 1, -3}, {-2, 0, 4}}, {{0, 20, 0}, {0, 0, 0}},  // straight down
      {{1, -5, 2}, {1, 5, 2}},                                                         // straight up
      {{-7, 3, 0.2f}, {8, 2.5f, -0.4f}},
  };
  for (const auto& c : cases) {
    place_camera(r, cam, c[0], c[1]);
    update_world_transforms(r);
    update_camera(r, cam, 16.0f / 9.0f);
    const Camera& camera = r.get<Camera>(cam);
    const glm::vec3 ndc = project(camera, c[1]);
    EXPECT_NEAR(ndc.x, 0.0f, 1e-4f);
    EXPECT_NEAR(ndc.y, 0.0f, 1e-4f);
    EXPECT_GT(ndc.z, 0.0f);
    EXPECT_LT(ndc.z, 1.0f);
    expect_vec3_near(world_position(r.get<Transform>(cam)), c[0]);
    // The rotation stays orthonormal.
    EXPECT_NEAR(glm::length(r.get<Transform>(cam).rotation), 1.0f, 1e-5f);
  }
}

TEST(Camera, ImageUpIsWorldUpAndYPointsDownInClipSpace) {
  Registry r;
  const Entity cam = make_camera(r);
  place_camera(r, cam, {0, 0, 10}, {0, 0, 0});
  update_world_transforms(r);
  update_camera(r, cam, 1.0f);
  const Camera& c = r.get<Camera>(cam);
  // Vulkan NDC y = -1 is the top row, so a point above the target has negative y, right is +x.
  EXPECT_LT(project(c, {0, 1, 0}).y, -0.05f);
  EXPECT_GT(project(c, {1, 0, 0}).x, 0.05f);
  // The camera looks down its -Z: its world basis has -Z towards the target.
  const glm::mat4& w = r.get<Transform>(cam).world;
  expect_vec3_near(-glm::vec3(w[2]), {0, 0, -1});
  expect_vec3_near(glm::vec3(w[1]), {0, 1, 0});
}

TEST(Camera, ReversedZMapsNearToOneAndFarToZero) {
  Registry r;
  const Entity cam = make_camera(r, 0.5f, 80.0f);
  place_camera(r, cam, {0, 0, 0}, {0, 0, -1});
  update_world_transforms(r);
  update_camera(r, cam, 1.5f);
  const Camera& c = r.get<Camera>(cam);
  EXPECT_NEAR(project(c, {0, 0, -0.5f}).z, 1.0f, 1e-5f);
  EXPECT_NEAR(project(c, {0, 0, -80.0f}).z, 0.0f, 1e-5f);
  const float near_depth = project(c, {0.1f, 0.2f, -3.0f}).z;
  const float far_depth = project(c, {0.1f, 0.2f, -30.0f}).z;
  EXPECT_GT(near_depth, far_depth);
  EXPECT_GT(far_depth, 0.0f);
  EXPECT_LT(near_depth, 1.0f);
  // Vertical field of view: a point at the top edge of the frustum lands on NDC y = -1.
  const float half = std::tan(c.vertical_fov * 0.5f) * 10.0f;
  EXPECT_NEAR(project(c, {0, half, -10.0f}).y, -1.0f, 1e-4f);
  EXPECT_NEAR(project(c, {half * 1.5f, 0, -10.0f}).x, 1.0f, 1e-4f);
}

TEST(Camera, ChildCameraFollowsItsParent) {
  Registry r;
  const Entity rig = r.create();
  Transform rt;
  rt.translation = {0, 0, 5};
  r.emplace<Transform>(rig, rt);
  const Entity cam = make_camera(r);
  r.get<Transform>(cam).parent = rig;
  update_world_transforms(r);
  update_camera(r, cam, 1.0f);
  // Identity local rotation: looks down -Z from (0,0,5), so the origin is straight ahead.
  const glm::vec3 ndc = project(r.get<Camera>(cam), {0, 0, 0});
  EXPECT_NEAR(ndc.x, 0.0f, 1e-5f);
  EXPECT_NEAR(ndc.y, 0.0f, 1e-5f);
  EXPECT_GT(ndc.z, 0.0f);
}

}  // namespace
