// The area-light reference (EmbreeTracer::area_visibility) against penumbrae worked out on paper, and
// the shared disc sampling (shared/area_light.h) the rt technique traces with.
#include <gtest/gtest.h>
#include <shared/area_light.h>
#include <shared/shadow_common.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "reference/embree_tracer.hpp"
#include "reference/synthetic.hpp"

namespace {

using reference::EmbreeTracer;
using reference::ShadingPoints;

constexpr glm::vec3 kUp(0.0f, 1.0f, 0.0f);
constexpr glm::vec3 kDown(0.0f, -1.0f, 0.0f);
constexpr double kPi = 3.14159265358979323846;

// The share of the unit disc on the far side of a chord at signed distance d from its centre (d <= -1:
// all of it, d >= 1: none): the segment's area acos(d) - d sqrt(1 - d^2) over pi.
double disc_share_beyond(double d) {
  if (d <= -1.0) return 1.0;
  if (d >= 1.0) return 0.0;
  return (std::acos(d) - d * std::sqrt(1.0 - d * d)) / kPi;
}

// A half-plane occluder at height 1 over x < 0 (its edge along z, 40 units each way) above ground
// points (x0, 0, z): under an overhead sun of angular radius r, the point sees the part of the sun's
// disc beyond the edge, whose direction tangents dx/dy fill a disc of radius tan(r) (the cone's cut by
// the plane one unit up along its axis): lit where dx/dy > -x0 / height.
constexpr float kEdgeHeight = 1.0f;

engine::Registry edge_scene() {
  engine::Registry reg;
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-40.0f), glm::vec2(40.0f)));
  reference::add_mesh_entity(reg, reference::make_quad_y(kEdgeHeight, glm::vec2(-40.0f), glm::vec2(0.0f, 40.0f)));
  return reg;
}

// One column per offset, `rows` rows (each pixel its own jitter), at z = row.
ShadingPoints points_at(const std::vector<float>& xs, uint32_t rows) {
  ShadingPoints sp;
  sp.resize(uint32_t(xs.size()), rows);
  sp.eye = glm::vec3(0.0f, 1.0f, 0.0f);  // a short shadow-ray offset (1/8192 here)
  for (uint32_t y = 0; y < rows; ++y)
    for (uint32_t x = 0; x < xs.size(); ++x) {
      sp.position[sp.index(x, y)] = glm::vec4(xs[x], 0.0f, float(y), 1.0f);
      sp.normal[sp.index(x, y)] = glm::vec4(kUp, 0.0f);
    }
  return sp;
}

TEST(AreaLight, SunPenumbraAcrossAStraightEdgeIsTheDiscSegment) {
  engine::Registry reg = edge_scene();
  const EmbreeTracer tracer(reg);
  const float diameter = 2.0f;
  const double tan_radius = std::tan(glm::radians(double(diameter) / 2.0));
  // Offsets in units of the penumbra's half width (height * tan(r)); +-5: far outside and inside.
  const std::vector<double> units{-5.0, -1.2, -0.9, -0.6, -0.3, 0.0, 0.3, 0.6, 0.9, 1.2, 5.0};
  std::vector<float> xs;
  for (double u : units) xs.push_back(float(u * kEdgeHeight * tan_radius));
  const ShadingPoints sp = points_at(xs, 4);
  const std::vector<float> vis = tracer.area_visibility(sp, kDown, diameter, 256);
  for (uint32_t y = 0; y < sp.height; ++y)
    for (uint32_t x = 0; x < sp.width; ++x) {
      SCOPED_TRACE(testing::Message() << "offset " << units[x] << " half widths, row " << y);
      const glm::vec3 origin = gpu_shared::shadow_ray_origin(glm::vec3(sp.position[sp.index(x, y)]), kUp,
                                                             gpu_shared::shadow_ray_offset(glm::vec3(sp.position[sp.index(x, y)]), sp.eye));
      const double height = kEdgeHeight - origin.y;
      const double expected = disc_share_beyond(-double(origin.x) / (height * tan_radius));
      const float v = vis[sp.index(x, y)];
      if (std::abs(units[x]) > 2.0) {
        EXPECT_EQ(v, units[x] > 0.0 ? 1.0f : 0.0f);
      } else {
        EXPECT_NEAR(v, expected, 0.03);
      }
    }
  // Averaged over the rows, the stratified estimate is closer still.
  for (uint32_t x = 0; x < sp.width; ++x) {
    double mean = 0.0;
    for (uint32_t y = 0; y < sp.height; ++y) mean += vis[sp.index(x, y)] / double(sp.height);
    EXPECT_NEAR(mean, disc_share_beyond(-units[x]), 0.015) << "offset " << units[x];
  }
}

// The same edge under a sun tilted across it (the rays' common origin conventions hold at any
// angle): the penumbra keeps its place around the hard shadow's edge, and the answer stays in [0, 1].
TEST(AreaLight, TiltedSunPenumbraStraddlesTheHardEdge) {
  engine::Registry reg = edge_scene();
  const EmbreeTracer tracer(reg);
  const glm::vec3 light = glm::normalize(glm::vec3(0.5f, -1.0f, 0.0f));  // the hard edge falls at x = 0.5
  std::vector<float> xs;
  for (int i = 0; i <= 80; ++i) xs.push_back(0.34f + 0.004f * float(i));
  const ShadingPoints sp = points_at(xs, 1);
  const std::vector<float> soft = tracer.area_visibility(sp, light, 3.0f, 256);
  const std::vector<float> hard = tracer.visibility_1spp(sp, light);
  int penumbra = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    SCOPED_TRACE(testing::Message() << "x " << xs[i]);
    EXPECT_GE(soft[i], 0.0f);
    EXPECT_LE(soft[i], 1.0f);
    if (i > 0) {  // rises across the edge (within the noise)
      EXPECT_GE(soft[i] + 0.05f, soft[i - 1]);
    }
    if (std::abs(xs[i] - 0.5f) > 0.1f) {
      EXPECT_EQ(soft[i], hard[i]);
    }
    penumbra += soft[i] > 0.02f && soft[i] < 0.98f;
  }
  EXPECT_GT(penumbra, 8);
}

// Ground y = 0 over [-4, 4]^2, occluder y = 1 over [-1, 1]^2, seen from above by 64 x 64 pixels.
engine::Registry ground_and_occluder() {
  engine::Registry reg;
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-4.0f), glm::vec2(4.0f)));
  reference::add_mesh_entity(reg, reference::make_quad_y(1.0f, glm::vec2(-1.0f), glm::vec2(1.0f)));
  return reg;
}
ShadingPoints ground_points(uint32_t size) {
  ShadingPoints sp = reference::plane_shading_points(
      size, size, reference::top_down_inv_view_proj(glm::vec2(0.0f), glm::vec2(4.0f)), glm::vec3(0.0f), kUp);
  for (uint32_t x = 0; x < size; ++x) sp.position[sp.index(x, 0)].w = 0.0f;  // a background row
  sp.normal[sp.index(3, 5)] = glm::vec4(kDown, 0.0f);                          // turned away from the light
  return sp;
}

TEST(AreaLight, SizeZeroIsTheOneRayAnswerBitForBit) {
  engine::Registry reg = ground_and_occluder();
  const EmbreeTracer tracer(reg);
  const ShadingPoints sp = ground_points(32);
  const glm::vec3 sun(0.3f, -1.0f, 0.2f);
  EXPECT_EQ(tracer.area_visibility(sp, sun, 0.0f, 256), tracer.visibility_1spp(sp, sun));
  EXPECT_EQ(tracer.area_visibility(sp, sun, 0.0f, 1), tracer.visibility_1spp(sp, sun));
  const reference::LocalLight point{.position = glm::vec3(0.4f, 3.0f, -0.2f), .range = 10.0f};
  EXPECT_EQ(tracer.area_visibility(sp, point, 0.0f, 256), tracer.visibility_1spp(sp, point));
  reference::LocalLight spot = point;
  spot.spot = true;
  spot.cos_outer = std::cos(0.8f);
  EXPECT_EQ(tracer.area_visibility(sp, spot, 0.0f, 64), tracer.visibility_1spp(sp, spot));
}

// The share of a disc light (centre `center`, `radius`, facing `origin`) whose segment from `origin`
// crosses the plane y = 1 outside [-1, 1]^2, integrated on a fine grid over the disc.
double disc_share_past_square(const glm::dvec3& origin, const glm::dvec3& center, double radius) {
  const glm::dvec3 axis = glm::normalize(center - origin);
  const glm::dvec3 u = glm::normalize(glm::cross(axis, glm::dvec3(0.0, 0.0, 1.0)));
  const glm::dvec3 v = glm::cross(axis, u);
  constexpr int kSteps = 300;
  int inside = 0, seen = 0;
  for (int i = 0; i < kSteps; ++i)
    for (int j = 0; j < kSteps; ++j) {
      const double a = (i + 0.5) / kSteps * 2.0 - 1.0, b = (j + 0.5) / kSteps * 2.0 - 1.0;
      if (a * a + b * b > 1.0) continue;
      ++inside;
      const glm::dvec3 target = center + radius * (a * u + b * v);
      const glm::dvec3 at = origin + (target - origin) * ((1.0 - origin.y) / (target.y - origin.y));
      seen += std::abs(at.x) > 1.0 || std::abs(at.z) > 1.0;
    }
  return double(seen) / double(inside);
}

// A point light 3 above the ground, radius 0.5, over the square occluder at height 1: ground points
// within 1.15 of the middle (in either axis) see none of it, those beyond 1.95 all of it (the disc's
// edges seen past the occluder's edges land between), and across the penumbra the reference follows
// the disc's share seen past the square, integrated on paper.
TEST(AreaLight, PointLightWithARadiusCastsAPenumbra) {
  engine::Registry reg = ground_and_occluder();
  const EmbreeTracer tracer(reg);
  constexpr uint32_t kSize = 64;  // pixels 0.125 wide; centres at -3.9375 + 0.125 i
  const ShadingPoints sp = ground_points(kSize);
  const reference::LocalLight light{.position = glm::vec3(0.0f, 3.0f, 0.0f), .range = 10.0f};
  const std::vector<float> vis = tracer.area_visibility(sp, light, 0.5f, 256);
  const std::vector<float> hard = tracer.visibility_1spp(sp, light);
  uint32_t penumbra = 0;
  for (uint32_t y = 0; y < kSize; ++y)
    for (uint32_t x = 0; x < kSize; ++x) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      const size_t i = sp.index(x, y);
      const float v = vis[i];
      if (y == 0 || (x == 3 && y == 5)) {
        EXPECT_EQ(v, hard[i]);  // background -1, turned away 0
        continue;
      }
      EXPECT_GE(v, 0.0f);
      EXPECT_LE(v, 1.0f);
      const glm::vec3 p(sp.position[i]);
      const float reach = std::max(std::abs(p.x), std::abs(p.z));
      if (reach < 1.15f) {
        EXPECT_EQ(v, 0.0f);
      }
      if (reach > 1.95f) {
        EXPECT_EQ(v, 1.0f);
      }
      if (v > 0.02f && v < 0.98f) {
        ++penumbra;
        EXPECT_GT(reach, 1.15f);
        EXPECT_LT(reach, 1.95f);
      }
    }
  EXPECT_GT(penumbra, 100u);
  // Across the penumbra's straight side (row 32: z = 0.0625) and across a corner (the diagonal).
  for (uint32_t x = 40; x < 48; ++x)
    for (const uint32_t y : {32u, x}) {
      SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
      const size_t i = sp.index(x, y);
      const glm::vec3 p(sp.position[i]);
      const glm::vec3 origin = gpu_shared::shadow_ray_origin(p, kUp, gpu_shared::shadow_ray_offset(p, sp.eye));
      EXPECT_NEAR(vis[i], disc_share_past_square(glm::dvec3(origin), glm::dvec3(light.position), 0.5), 0.03);
    }
}

TEST(AreaLight, RejectsBadInput) {
  engine::Registry reg = ground_and_occluder();
  const EmbreeTracer tracer(reg);
  const ShadingPoints sp = ground_points(8);
  const reference::LocalLight light{.position = glm::vec3(0.0f, 3.0f, 0.0f), .range = 10.0f};
  EXPECT_THROW(tracer.area_visibility(sp, kDown, 1.0f, 0), std::invalid_argument);
  EXPECT_THROW(tracer.area_visibility(sp, kDown, -1.0f, 16), std::invalid_argument);
  EXPECT_THROW(tracer.area_visibility(sp, kDown, NAN, 16), std::invalid_argument);
  EXPECT_THROW(tracer.area_visibility(sp, glm::vec3(0.0f), 1.0f, 16), std::invalid_argument);
  EXPECT_THROW(tracer.area_visibility(sp, light, 0.1f, 0), std::invalid_argument);
  EXPECT_THROW(tracer.area_visibility(sp, light, -0.1f, 16), std::invalid_argument);
  ShadingPoints short_points = sp;
  short_points.normal.pop_back();
  EXPECT_THROW(tracer.area_visibility(short_points, kDown, 1.0f, 16), std::invalid_argument);
}

// Ray counts that are not squares stratify too: a light no occluder blocks is seen whole, one that a
// large occluder blocks not at all, for any count.
TEST(AreaLight, AnyRayCountStratifies) {
  engine::Registry reg = ground_and_occluder();
  const EmbreeTracer tracer(reg);
  const ShadingPoints sp = ground_points(16);
  const std::vector<float> hard = tracer.visibility_1spp(sp, kDown);
  for (uint32_t rays : {1u, 2u, 3u, 7u, 50u, 256u, 300u}) {
    SCOPED_TRACE(testing::Message() << rays << " rays");
    const std::vector<float> vis = tracer.area_visibility(sp, kDown, 1.0f, rays);
    for (uint32_t y = 1; y < 16; ++y)
      for (uint32_t x = 0; x < 16; ++x) {
        const size_t i = sp.index(x, y);
        const glm::vec3 p(sp.position[i]);
        const float reach = std::max(std::abs(p.x), std::abs(p.z));
        if (reach < 0.9f || reach > 1.1f) {
          EXPECT_EQ(vis[i], hard[i]) << "pixel " << x << "," << y;
        }
      }
  }
}

// ---- shared/area_light.h, as the rt technique uses it ----

TEST(AreaLightSampling, SpiralCoversTheUnitDiscEvenly) {
  for (uint32_t n : {1u, 4u, 16u, 64u}) {
    for (float rotation : {0.0f, 1.3f, 5.9f}) {
      glm::dvec2 mean(0.0);
      uint32_t inner = 0;
      for (uint32_t k = 0; k < n; ++k) {
        const glm::vec2 d = gpu_shared::area_light_disc_sample(k, n, rotation);
        EXPECT_LE(glm::length(d), 1.0f + 1e-6f);
        mean += glm::dvec2(d) / double(n);
        inner += glm::length(d) < std::sqrt(0.5f);
      }
      if (n > 1) {  // equal area: half the samples within radius sqrt(1/2)
        EXPECT_EQ(inner, n / 2) << n;
      }
      if (n >= 16) {
        EXPECT_LT(glm::length(mean), 0.05) << n;
      }
    }
  }
  for (uint32_t x = 0; x < 64; ++x) {
    const float r = gpu_shared::area_light_rotation(glm::uvec2(x, 7u * x + 3u));
    EXPECT_GE(r, 0.0f);
    EXPECT_LT(r, 6.2832f);
  }
  EXPECT_NE(gpu_shared::area_light_hash(glm::uvec2(0, 0)), gpu_shared::area_light_hash(glm::uvec2(1, 0)));
  EXPECT_NE(gpu_shared::area_light_hash(glm::uvec2(1, 0)), gpu_shared::area_light_hash(glm::uvec2(0, 1)));
}

TEST(AreaLightSampling, BasisConeAndDiscPointsAreWhereTheySay) {
  const glm::vec3 axes[] = {glm::vec3(0, 0, 1),  glm::vec3(0, 0, -1), glm::vec3(1, 0, 0),
                            glm::vec3(0, 1, 0),  glm::vec3(0, -1, 0), glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)),
                            glm::normalize(glm::vec3(-2.0f, 0.1f, -1e-4f))};
  const float tan_radius = std::tan(glm::radians(2.5f));
  const float cone = gpu_shared::area_light_cone(tan_radius);
  EXPECT_NEAR(cone, 1.0 - std::cos(glm::radians(2.5)), 1e-9);
  for (const glm::vec3& axis : axes) {
    SCOPED_TRACE(testing::Message() << "axis " << axis.x << "," << axis.y << "," << axis.z);
    const glm::vec3 t = gpu_shared::area_light_tangent(axis), b = gpu_shared::area_light_bitangent(axis);
    EXPECT_NEAR(glm::length(t), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::length(b), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(t, axis), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(b, axis), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(t, b), 0.0f, 1e-5f);
    for (uint32_t k = 0; k < 64; ++k) {
      const glm::vec2 d = gpu_shared::area_light_disc_sample(k, 64, 0.7f);
      const glm::vec3 dir = gpu_shared::area_light_cone_direction(axis, cone, d);
      EXPECT_NEAR(glm::length(dir), 1.0f, 1e-5f);
      // The angle to the axis grows with the sample's radius: 1 - cos = |d|^2 cone.
      EXPECT_NEAR(1.0 - double(glm::dot(dir, axis)), double(glm::dot(d, d)) * cone, 2e-6);
      const glm::vec3 q = gpu_shared::area_light_disc_point(glm::vec3(1, 2, 3), axis, 0.5f, d);
      EXPECT_NEAR(glm::length(q - glm::vec3(1, 2, 3)), 0.5f * glm::length(d), 1e-5f);
      EXPECT_NEAR(glm::dot(q - glm::vec3(1, 2, 3), axis), 0.0f, 1e-5f);
    }
  }
}

// The rt technique's 64 spiral rays against the straight edge, traced on paper: every pixel's estimate
// stays near the disc segment, whatever its rotation.
TEST(AreaLightSampling, SixtyFourSpiralRaysEstimateTheDiscSegment) {
  const float tan_radius = std::tan(glm::radians(1.0f));
  const float cone = gpu_shared::area_light_cone(tan_radius);
  double worst = 0.0;
  for (double d = -1.0; d <= 1.0; d += 0.125)
    for (uint32_t pixel = 0; pixel < 32; ++pixel) {
      const float rotation = gpu_shared::area_light_rotation(glm::uvec2(pixel, 11u));
      uint32_t lit = 0;
      for (uint32_t k = 0; k < 64; ++k) {
        const glm::vec3 dir = gpu_shared::area_light_cone_direction(kUp, cone, gpu_shared::area_light_disc_sample(k, 64, rotation));
        lit += double(dir.x / dir.y) > d * double(tan_radius);
      }
      worst = std::max(worst, std::abs(double(lit) / 64.0 - disc_share_beyond(d)));
    }
  EXPECT_LT(worst, 0.06);
}

}  // namespace
