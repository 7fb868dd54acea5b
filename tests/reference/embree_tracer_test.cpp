// The reference tracer checked against shadows worked out by hand, on scenes built in code.
#include "reference/embree_tracer.hpp"

#include <gtest/gtest.h>
#include <shared/shadow_common.h>

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <stdexcept>

#include "reference/synthetic.hpp"

namespace {

using reference::EmbreeTracer;
using reference::ShadingPoints;

constexpr glm::vec3 kUp(0.0f, 1.0f, 0.0f);
constexpr glm::vec3 kDown(0.0f, -1.0f, 0.0f);
constexpr uint32_t kSize = 16;  // 16 x 16 pixels over [-4, 4]^2: each pixel is 0.5 world units wide

// Ground y = 0 over [-4, 4]^2, occluder y = 1 over [-1, 1]^2: with light straight down, pixels 6..9
// in both x and y are under the occluder.
void add_ground_and_occluder(engine::Registry& reg) {
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-4.0f), glm::vec2(4.0f)));
  reference::add_mesh_entity(reg, reference::make_quad_y(1.0f, glm::vec2(-1.0f), glm::vec2(1.0f)));
}

glm::mat4 camera() { return reference::top_down_inv_view_proj(glm::vec2(0.0f), glm::vec2(4.0f)); }

bool under_occluder(uint32_t x, uint32_t y) { return x >= 6 && x <= 9 && y >= 6 && y <= 9; }

float at(const std::vector<float>& v, uint32_t x, uint32_t y) { return v[size_t(y) * kSize + x]; }

TEST(EmbreeTracer, TakesMeshesWithTransformThatCastShadows) {
  engine::Registry reg;
  add_ground_and_occluder(reg);  // no ShadowCaster: cast
  const auto caster = reference::add_mesh_entity(
      reg, reference::make_quad_y(2.0f, glm::vec2(0.0f), glm::vec2(1.0f)));
  reg.emplace<engine::ShadowCaster>(caster, engine::ShadowCaster{.casts_shadow = true});
  const auto hidden = reference::add_mesh_entity(
      reg, reference::make_quad_y(3.0f, glm::vec2(0.0f), glm::vec2(1.0f)));
  reg.emplace<engine::ShadowCaster>(hidden, engine::ShadowCaster{.casts_shadow = false});
  const auto no_transform = reg.create();
  reg.emplace<engine::Mesh>(
      no_transform, engine::Mesh{reference::make_quad_y(4.0f, glm::vec2(0.0f), glm::vec2(1.0f))});
  reg.emplace<engine::Transform>(reg.create());
  reference::add_mesh_entity(reg, nullptr);  // a Mesh without data

  const EmbreeTracer tracer(reg);
  EXPECT_EQ(tracer.triangle_count(), 6u);
  // The quad at y = 3 was left out; the one at y = 2 was not.
  EXPECT_TRUE(tracer.occluded(glm::vec3(0.5f, 2.5f, 0.5f), kDown));
  EXPECT_FALSE(tracer.occluded(glm::vec3(0.5f, 2.5f, 0.5f), kUp));
}

TEST(EmbreeTracer, AppliesWorldMatrixAndSeesBothFaces) {
  engine::Registry reg;
  // A unit quad at the origin, scaled to [-1, 1]^2 and lifted to y = 1 by its world matrix alone.
  const glm::mat4 world =
      glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0f, 0.0f)), glm::vec3(2.0f));
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-0.5f), glm::vec2(0.5f)),
                             world);
  const EmbreeTracer tracer(reg);
  EXPECT_EQ(tracer.triangle_count(), 2u);
  EXPECT_TRUE(tracer.occluded(glm::vec3(0.9f, 0.0f, -0.9f), kUp));    // hits the back face
  EXPECT_TRUE(tracer.occluded(glm::vec3(-0.9f, 2.0f, 0.9f), kDown));  // hits the front face
  EXPECT_FALSE(tracer.occluded(glm::vec3(1.1f, 0.0f, 0.0f), kUp));
  EXPECT_FALSE(tracer.occluded(glm::vec3(0.0f, 0.0f, 0.0f), kDown));
  EXPECT_FALSE(tracer.occluded(glm::vec3(0.0f, 1.5f, 0.0f), kUp));
}

TEST(EmbreeTracer, OneSampleGroundShadowBackgroundAndBackFacing) {
  engine::Registry reg;
  add_ground_and_occluder(reg);
  const EmbreeTracer tracer(reg);
  ShadingPoints sp = reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0.0f), kUp);
  for (uint32_t x = 0; x < kSize; ++x) sp.position[sp.index(x, 0)].w = 0.0f;  // a background row
  sp.normal[sp.index(2, 3)] = glm::vec4(kDown, 0.0f);  // faces away from the sun
  sp.normal[sp.index(7, 7)] = glm::vec4(kDown, 0.0f);  // faces away and is under the occluder

  const std::vector<float> vis = tracer.visibility_1spp(sp, glm::vec3(0.0f, -2.0f, 0.0f));
  ASSERT_EQ(vis.size(), size_t(kSize) * kSize);
  for (uint32_t y = 0; y < kSize; ++y) {
    for (uint32_t x = 0; x < kSize; ++x) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      float expected = under_occluder(x, y) ? 0.0f : 1.0f;
      if (y == 0) expected = -1.0f;
      if (x == 2 && y == 3) expected = 0.0f;
      EXPECT_EQ(at(vis, x, y), expected);
    }
  }
  // The occluder's edges fall on pixel boundaries, so all 32 samples of a pixel agree.
  EXPECT_EQ(tracer.visibility_32spp(sp, glm::vec3(0.0f, -2.0f, 0.0f)), vis);
}

// A light 3 above the ground at the origin and the occluder at height 1: a ground point (x, 0, z) is
// shadowed when its ray crosses y = 1 inside [-1, 1]^2, i.e. |x|, |z| <= 1.5: pixels 5..10. A quad
// 0.002 under the light (within the bulb, range / 1000, along every ray here: at most 0.0041) and one above
// the light shadow nothing.
TEST(EmbreeTracer, PointLightShadowsWhatItsRaysCross) {
  engine::Registry reg;
  add_ground_and_occluder(reg);
  reference::add_mesh_entity(reg, reference::make_quad_y(2.998f, glm::vec2(-0.5f), glm::vec2(0.5f)));
  reference::add_mesh_entity(reg, reference::make_quad_y(4.0f, glm::vec2(-4.0f), glm::vec2(4.0f)));
  const EmbreeTracer tracer(reg);
  ShadingPoints sp = reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0.0f), kUp);
  sp.normal[sp.index(2, 3)] = glm::vec4(kDown, 0.0f);  // faces away from the light
  const reference::LocalLight light{.position = glm::vec3(0.0f, 3.0f, 0.0f), .range = 10.0f};
  const std::vector<float> vis = tracer.visibility_1spp(sp, light);
  for (uint32_t y = 0; y < kSize; ++y)
    for (uint32_t x = 0; x < kSize; ++x) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      const bool under = x >= 5 && x <= 10 && y >= 5 && y <= 10;
      EXPECT_EQ(at(vis, x, y), under || (x == 2 && y == 3) ? 0.0f : 1.0f);
    }
  // The shadow's edges (|x| = 1.5) fall on pixel boundaries, so all 32 samples of a pixel agree.
  EXPECT_EQ(tracer.visibility_32spp(sp, light), vis);
}

// Range and cone: a point light of range 4 reaches ground points within sqrt(7) of the origin; a spot
// light pointing down with a 45 degree outer cone, those within 3.
TEST(EmbreeTracer, LocalLightsReachOnlyTheirRangeAndCone) {
  engine::Registry reg;
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-4.0f), glm::vec2(4.0f)));
  const EmbreeTracer tracer(reg);
  const ShadingPoints sp = reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0.0f), kUp);
  const reference::LocalLight point{.position = glm::vec3(0.0f, 3.0f, 0.0f), .range = 4.0f};
  const reference::LocalLight spot{.position = glm::vec3(0.0f, 3.0f, 0.0f), .range = 10.0f, .spot = true,
                                   .spot_direction = kDown, .cos_outer = std::cos(glm::radians(45.0f))};
  const std::vector<float> by_point = tracer.visibility_1spp(sp, point);
  const std::vector<float> by_spot = tracer.visibility_1spp(sp, spot);
  size_t reached_by_point = 0, reached_by_spot = 0;
  for (uint32_t y = 0; y < kSize; ++y)
    for (uint32_t x = 0; x < kSize; ++x) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      const float r = glm::length(glm::vec2(-3.75f + 0.5f * float(x), -3.75f + 0.5f * float(y)));
      EXPECT_EQ(at(by_point, x, y), r * r + 9.0f <= 16.0f ? 1.0f : 0.0f);
      EXPECT_EQ(at(by_spot, x, y), r <= 3.0f ? 1.0f : 0.0f);
      reached_by_point += at(by_point, x, y) == 1.0f;
      reached_by_spot += at(by_spot, x, y) == 1.0f;
    }
  EXPECT_GT(reached_by_point, 0u);
  EXPECT_LT(reached_by_point, reached_by_spot);
}

// The offset follows the coordinates' scale and the camera's distance (shadow_ray_offset), so the same
// configuration answers the same at a millimetre, a metre or a kilometre per unit, and far from the
// origin: each scene here is the one at scale 1 scaled by `scale` and moved by `shift`.
TEST(EmbreeTracer, RayStartsAtSharedNormalOffsetAtEveryScale) {
  for (const float scale : {0.01f, 1.0f, 100.0f, 1000.0f}) {
    for (const float shift : {0.0f, 1.0e3f, 1.0e4f}) {
      SCOPED_TRACE(testing::Message() << "scale " << scale << ", shift " << shift);
      const glm::vec3 move(shift, 0.0f, shift);
      engine::Registry reg;
      reference::add_mesh_entity(reg, reference::make_quad_y(scale, glm::vec2(-scale) + shift, glm::vec2(scale) + shift));
      const EmbreeTracer tracer(reg);
      ShadingPoints sp;
      sp.resize(4, 1);
      sp.eye = move + glm::vec3(0.0f, 3.0f * scale, 0.0f);
      const glm::vec3 surface = move + glm::vec3(0.0f, scale, 0.0f);
      const float k = gpu_shared::shadow_ray_offset(surface, sp.eye);
      // Just under the surface, within the offset: the pushed origin clears it.
      sp.position[0] = glm::vec4(surface - glm::vec3(0.0f, 0.5f * k, 0.0f), 1.0f);
      // Under the surface by more than the offset: still below it, so shadowed.
      sp.position[1] = glm::vec4(surface - glm::vec3(0.0f, 2.0f * k, 0.0f), 1.0f);
      // Exactly on it: no self-shadowing.
      sp.position[2] = glm::vec4(surface, 1.0f);
      // Normal perpendicular to the light counts as facing away.
      sp.position[3] = glm::vec4(move + glm::vec3(5.0f * scale, 0.0f, 0.0f), 1.0f);
      for (int i = 0; i < 3; ++i) sp.normal[i] = glm::vec4(kUp, 0.0f);
      sp.normal[3] = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
      const std::vector<float> vis = tracer.visibility_1spp(sp, kDown);
      EXPECT_EQ(vis, (std::vector<float>{1.0f, 0.0f, 1.0f, 0.0f}));
      // With an identity inv_view_proj the camera rays run parallel to these planes, so every μQuad
      // sample stays at its shading point and 32 samples must give the same answers.
      EXPECT_EQ(tracer.visibility_32spp(sp, kDown), vis);
      // The offset is a few thousand ulps of the coordinates at hand, whatever their size.
      const float ulp = std::nextafter(std::max(std::abs(surface.x), surface.y), 1.0e30f) - std::max(std::abs(surface.x), surface.y);
      EXPECT_GT(k, 256.0f * ulp);
      EXPECT_LT(k, 1.0e-3f * (3.0f * scale + shift) + 8192.0f * ulp);
    }
  }
}

// A world far from its origin, rebased: entities a million units out, traced relative to a local
// origin beside them (the tracer's shift, computed in double), answer as the same scene at the origin.
TEST(EmbreeTracer, RebasedWorldAnswersAsAtTheOrigin) {
  const auto build = [](glm::dvec3 where, engine::Registry& reg) {
    const engine::Entity e = reference::add_mesh_entity(reg, reference::make_quad_y(1.0f, glm::vec2(-1.0f), glm::vec2(1.0f)));
    reg.get<engine::Transform>(e).world[3] = glm::vec4(glm::vec3(where), 1.0f);
  };
  engine::Registry at_origin, far_away;
  build(glm::dvec3(0.0), at_origin);
  const glm::dvec3 far(1.0e6, 0.0, -1.0e6);
  build(far, far_away);
  const EmbreeTracer near_tracer(at_origin), rebased(far_away, -far);
  ShadingPoints sp = reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0.0f), kUp);
  const glm::vec3 light(0.3f, -1.0f, 0.2f);
  const auto expected = near_tracer.visibility_1spp(sp, light);
  EXPECT_EQ(rebased.visibility_1spp(sp, light), expected);
  EXPECT_EQ(rebased.visibility_32spp(sp, light), near_tracer.visibility_32spp(sp, light));
  EXPECT_GT(std::count(expected.begin(), expected.end(), 0.0f), 10);
  // Without the shift the far scene is somewhere else entirely: nothing shadows the points.
  const EmbreeTracer unshifted(far_away);
  const auto none = unshifted.visibility_1spp(sp, light);
  EXPECT_EQ(std::count(none.begin(), none.end(), 0.0f), 0);
}

TEST(EmbreeTracer, FlippedLightFlipsPointsUnderTheOccluder) {
  engine::Registry reg;
  reference::add_mesh_entity(reg, reference::make_quad_y(1.0f, glm::vec2(-1.0f), glm::vec2(1.0f)));
  const EmbreeTracer tracer(reg);
  // Receivers floating at y = 0.5, below the occluder, with nothing under them.
  const ShadingPoints facing_up =
      reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0, 0.5f, 0), kUp);
  const ShadingPoints facing_down =
      reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0, 0.5f, 0), kDown);
  const std::vector<float> sun_above = tracer.visibility_1spp(facing_up, kDown);
  const std::vector<float> sun_below = tracer.visibility_1spp(facing_down, kUp);
  const std::vector<float> sun_below_facing_up = tracer.visibility_1spp(facing_up, kUp);
  // Above the occluder looking down on it, with the sun below: its front face shadows.
  const ShadingPoints above =
      reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0, 1.5f, 0), kDown);
  const std::vector<float> above_sun_below = tracer.visibility_1spp(above, kUp);
  for (uint32_t y = 0; y < kSize; ++y) {
    for (uint32_t x = 0; x < kSize; ++x) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      EXPECT_EQ(at(sun_above, x, y), under_occluder(x, y) ? 0.0f : 1.0f);
      EXPECT_EQ(at(sun_below, x, y), 1.0f);
      EXPECT_EQ(at(sun_below_facing_up, x, y), 0.0f);
      EXPECT_EQ(at(above_sun_below, x, y), under_occluder(x, y) ? 0.0f : 1.0f);
    }
  }
}

TEST(EmbreeTracer, MicroQuadSamplesLandWhereTheCameraPutsThem) {
  const glm::vec2 viewport{float(kSize)};
  const glm::vec3 s =
      gpu_shared::micro_quad_sample(glm::vec2(6.0f, 9.0f), gpu_shared::kSamplePattern[5], viewport,
                                    camera(), glm::vec3(1.0f, 0.0f, 2.0f), kUp);
  EXPECT_NEAR(s.x, -4.0f + 0.5f * (6.0f + gpu_shared::kSamplePattern[5].x), 1e-5f);
  EXPECT_NEAR(s.y, 0.0f, 1e-5f);
  EXPECT_NEAR(s.z, -4.0f + 0.5f * (9.0f + gpu_shared::kSamplePattern[5].y), 1e-5f);
}

// 32 samples under a tilted sun: the shadow of the occluder's x edges falls inside pixel columns 6
// and 10, so those are fractional; every value must match an analytic ray/plane test per sample.
TEST(EmbreeTracer, ThirtyTwoSamplesMatchAnalyticShadow) {
  engine::Registry reg;
  add_ground_and_occluder(reg);
  const EmbreeTracer tracer(reg);
  const glm::vec3 light(0.3f, -1.0f, 0.0f);
  const ShadingPoints sp =
      reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0.0f), kUp);
  const std::vector<float> vis = tracer.visibility_32spp(sp, light);
  const std::vector<float> one = tracer.visibility_1spp(sp, light);

  const glm::vec3 to_light = -glm::normalize(light);
  auto lit_analytic = [&](glm::vec3 surface) {
    const glm::vec3 o = gpu_shared::shadow_ray_origin(surface, kUp, gpu_shared::shadow_ray_offset(surface, sp.eye));
    const glm::vec3 h = o + to_light * ((1.0f - o.y) / to_light.y);
    return !(std::abs(h.x) <= 1.0f && std::abs(h.z) <= 1.0f);
  };
  int fractional = 0;
  for (uint32_t y = 0; y < kSize; ++y) {
    for (uint32_t x = 0; x < kSize; ++x) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      int lit = 0;
      for (const glm::vec2& offset : gpu_shared::kSamplePattern) {
        lit += lit_analytic(glm::vec3(-4.0f + 0.5f * (float(x) + offset.x), 0.0f,
                                      -4.0f + 0.5f * (float(y) + offset.y)));
      }
      EXPECT_FLOAT_EQ(at(vis, x, y), float(lit) / 32.0f);
      EXPECT_EQ(at(one, x, y), lit_analytic(glm::vec3(sp.position[sp.index(x, y)])) ? 1.0f : 0.0f);
      const bool edge_column = (x == 6 || x == 10) && y >= 6 && y <= 9;
      if (edge_column) {
        EXPECT_GT(at(vis, x, y), 0.0f);
        EXPECT_LT(at(vis, x, y), 1.0f);
        ++fractional;
      } else {
        EXPECT_TRUE(at(vis, x, y) == 0.0f || at(vis, x, y) == 1.0f);
      }
    }
  }
  EXPECT_EQ(fractional, 8);
  // Counted by hand from kSamplePattern: the shadow edge sits at x = -0.7006 (19 samples left of
  // it, lit) and x = 1.2994 (19 samples left of it, shadowed).
  EXPECT_FLOAT_EQ(at(vis, 6, 8), 19.0f / 32.0f);
  EXPECT_FLOAT_EQ(at(vis, 10, 8), 13.0f / 32.0f);
  EXPECT_EQ(at(one, 6, 8), 1.0f);
  EXPECT_EQ(at(one, 10, 8), 0.0f);
}

TEST(EmbreeTracer, PacketResultsAgreeWithSingleRays) {
  engine::Registry reg;
  add_ground_and_occluder(reg);
  reference::add_mesh_entity(
      reg, reference::make_quad_y(2.0f, glm::vec2(1.5f, -3.0f), glm::vec2(3.0f, 0.5f)));
  const EmbreeTracer tracer(reg);
  const glm::vec3 light = glm::normalize(glm::vec3(-0.7f, -1.0f, 0.45f));
  const ShadingPoints sp =
      reference::plane_shading_points(kSize, kSize, camera(), glm::vec3(0.0f), kUp);
  const std::vector<float> vis = tracer.visibility_1spp(sp, light);
  int shadowed = 0;
  for (size_t i = 0; i < vis.size(); ++i) {
    const glm::vec3 o = gpu_shared::shadow_ray_origin(glm::vec3(sp.position[i]), kUp, gpu_shared::shadow_ray_offset(glm::vec3(sp.position[i]), sp.eye));
    EXPECT_EQ(vis[i], tracer.occluded(o, -light) ? 0.0f : 1.0f) << "pixel " << i;
    shadowed += vis[i] == 0.0f;
  }
  EXPECT_GT(shadowed, 20);
}

TEST(EmbreeTracer, EmptySceneLightsEverything) {
  engine::Registry reg;
  const EmbreeTracer tracer(reg);
  EXPECT_EQ(tracer.triangle_count(), 0u);
  const ShadingPoints sp = reference::plane_shading_points(4, 4, camera(), glm::vec3(0.0f), kUp);
  EXPECT_EQ(tracer.visibility_32spp(sp, kDown), std::vector<float>(16, 1.0f));
}

TEST(EmbreeTracer, RejectsBadInput) {
  engine::Registry reg;
  auto bad = reference::make_quad_y(0.0f, glm::vec2(0.0f), glm::vec2(1.0f));
  bad->indices.push_back(0);
  bad->indices.push_back(1);
  bad->indices.push_back(7);
  reference::add_mesh_entity(reg, bad);
  EXPECT_THROW(EmbreeTracer{reg}, std::runtime_error);

  engine::Registry empty;
  const EmbreeTracer tracer(empty);
  ShadingPoints sp = reference::plane_shading_points(4, 4, camera(), glm::vec3(0.0f), kUp);
  EXPECT_THROW(tracer.visibility_1spp(sp, glm::vec3(0.0f)), std::invalid_argument);
  sp.normal.pop_back();
  EXPECT_THROW(tracer.visibility_32spp(sp, kDown), std::invalid_argument);
}

}  // namespace

// The independent reference (its own hits, normals, facing, reach and ray starts, in double) against
// shadows worked out by hand: a perspective camera over a floor (y = 0) with a card at y = 1 over
// [-1, 1]^2, lit by a slanted sun and by a slanted spot light. Pixels whose hand-worked answer lies
// within 1e-4 of a card edge or 1e-5 of the cone's cosine are left out; every other is exact.
namespace independent {

constexpr uint32_t kPixels = 96;
constexpr double kCardHeight = 1.0;

struct HandWorked {
  bool covered = false;
  bool on_card = false;
  glm::dvec3 point{0.0};
};

reference::PinholeCamera perspective_camera() {
  reference::PinholeCamera camera;
  camera.eye = glm::dvec3(0.5, 6.0, 7.0);
  const glm::dmat4 view = glm::lookAt(camera.eye, glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0));
  glm::dmat4 projection = glm::perspective(glm::radians(60.0), 1.0, 0.1, 100.0);
  projection[1][1] *= -1.0;  // Vulkan's y down
  camera.inv_view_proj = glm::inverse(projection * view);
  camera.width = camera.height = kPixels;
  return camera;
}

// The floor or card point pixel (x, y)'s centre shows, by intersecting planes.
HandWorked hand_worked_point(const reference::PinholeCamera& camera, uint32_t x, uint32_t y) {
  const glm::dvec4 ndc((x + 0.5) / kPixels * 2.0 - 1.0, (y + 0.5) / kPixels * 2.0 - 1.0, 0.5, 1.0);
  const glm::dvec4 far = camera.inv_view_proj * ndc;
  const glm::dvec3 dir = glm::normalize(glm::dvec3(far) / far.w - camera.eye);
  HandWorked h;
  const glm::dvec3 card = camera.eye + dir * ((kCardHeight - camera.eye.y) / dir.y);
  if (std::abs(card.x) <= 1.0 && std::abs(card.z) <= 1.0) {
    h.covered = h.on_card = true;
    h.point = card;
    return h;
  }
  h.point = camera.eye + dir * (-camera.eye.y / dir.y);
  h.covered = std::abs(h.point.x) <= 8.0 && std::abs(h.point.z) <= 8.0;
  return h;
}

// Where the segment from a floor point toward `target` (a point above the card) crosses y = 1: under
// the card (1), clear of it (0), or within 1e-4 of an edge (-1).
int card_blocks(const glm::dvec3& floor_point, const glm::dvec3& toward) {
  const glm::dvec3 at = floor_point + toward * ((kCardHeight - floor_point.y) / toward.y);
  const double inside = 1.0 - std::max(std::abs(at.x), std::abs(at.z));
  if (std::abs(inside) < 1.0e-4) return -1;
  return inside > 0.0 ? 1 : 0;
}

void add_floor_and_card(engine::Registry& reg) {
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-8.0f), glm::vec2(8.0f)));
  reference::add_mesh_entity(reg, reference::make_quad_y(float(kCardHeight), glm::vec2(-1.0f), glm::vec2(1.0f)));
}

}  // namespace independent

TEST(EmbreeTracer, IndependentReferenceMatchesAHandWorkedSunAndPerspectiveCamera) {
  using namespace independent;
  engine::Registry reg;
  add_floor_and_card(reg);
  const EmbreeTracer tracer(reg);
  const reference::PinholeCamera camera = perspective_camera();
  reference::TrueLight sun;
  sun.direction = glm::dvec3(0.35, -1.0, 0.2);
  const glm::dvec3 to_sun = -glm::normalize(sun.direction);
  const auto truth = tracer.independent_visibility(camera, sun, 1, 1.0 / 4096.0);
  size_t checked = 0, shadowed = 0;
  for (uint32_t y = 0; y < kPixels; ++y)
    for (uint32_t x = 0; x < kPixels; ++x) {
      const HandWorked h = hand_worked_point(camera, x, y);
      const reference::TrueVisibility& t = truth[size_t(y) * kPixels + x];
      ASSERT_EQ(t.covered(), h.covered) << x << "," << y;
      if (!h.covered) continue;
      EXPECT_LT(glm::length(t.point - h.point), 1.0e-9 * 16.0) << x << "," << y;
      const int blocked = h.on_card ? 0 : card_blocks(h.point, to_sun);
      if (blocked < 0) continue;
      const float expected = blocked ? 0.0f : 1.0f;
      EXPECT_EQ(t.lit_min, expected) << x << "," << y;
      EXPECT_EQ(t.lit_max, expected) << x << "," << y;
      ++checked;
      shadowed += blocked;
    }
  EXPECT_GT(checked, kPixels * kPixels / 2);
  EXPECT_GT(shadowed, 100u);
}

TEST(EmbreeTracer, IndependentReferenceMatchesAHandWorkedSlantedSpotLight) {
  using namespace independent;
  engine::Registry reg;
  add_floor_and_card(reg);
  const EmbreeTracer tracer(reg);
  const reference::PinholeCamera camera = perspective_camera();
  reference::TrueLight spot;
  spot.sun = false;
  spot.spot = true;
  spot.position = glm::dvec3(3.0, 4.0, 1.5);
  spot.spot_direction = glm::dvec3(-0.6, -1.0, -0.3);
  spot.outer_cone = glm::radians(28.0);
  spot.range = 5.5;
  const auto truth = tracer.independent_visibility(camera, spot, 1, 1.0 / 4096.0);
  const double cos_outer = std::cos(spot.outer_cone);
  size_t checked = 0, lit = 0, outside_cone = 0, beyond_range = 0, shadowed = 0;
  for (uint32_t y = 0; y < kPixels; ++y)
    for (uint32_t x = 0; x < kPixels; ++x) {
      const HandWorked h = hand_worked_point(camera, x, y);
      const reference::TrueVisibility& t = truth[size_t(y) * kPixels + x];
      ASSERT_EQ(t.covered(), h.covered) << x << "," << y;
      if (!h.covered) continue;
      const glm::dvec3 from_light = h.point - spot.position;
      const double distance = glm::length(from_light);
      const double cos_angle = glm::dot(from_light / distance, glm::normalize(spot.spot_direction));
      if (std::abs(cos_angle - cos_outer) < 1.0e-5 || std::abs(distance - spot.range) < 1.0e-5) continue;
      float expected = 1.0f;
      if (cos_angle < cos_outer) {
        expected = 0.0f;
        ++outside_cone;
      } else if (distance > spot.range) {
        expected = 0.0f;
        ++beyond_range;
      } else if (!h.on_card) {
        const int blocked = card_blocks(h.point, spot.position - h.point);
        if (blocked < 0) continue;
        if (blocked) {
          expected = 0.0f;
          ++shadowed;
        }
      }
      EXPECT_EQ(t.lit_min, expected) << x << "," << y;
      EXPECT_EQ(t.lit_max, expected) << x << "," << y;
      ++checked;
      lit += expected > 0.0f;
    }
  EXPECT_GT(checked, kPixels * kPixels / 2);
  // The picture holds each case: lit, outside the cone, beyond the range, behind the card.
  EXPECT_GT(lit, 300u);
  EXPECT_GT(outside_cone, 300u);
  EXPECT_GT(beyond_range, 20u);
  EXPECT_GT(shadowed, 30u);
}
