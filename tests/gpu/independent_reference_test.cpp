// The module against a reference of its own (EmbreeTracer::independent_visibility): each pixel's true
// lit fraction found without the module's shader code (its own primary-ray hits, normals, facing, light
// reach and ray starts, in double), as bounds that allow the shadow ray to start anywhere up to twice
// the module's documented offset (1/8192 of |p|inf + |p - eye|inf) off the surface. A ray offset beyond
// that, or a cone or range wider than the light's, fails here, where the rest of the suite's reference
// (which shares the module's conventions) would follow it. Pixels whose rasterized point is another
// surface than the pixel centre's ray hit (silhouettes) are left out and counted.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

#include "frame_capture.hpp"
#include "gpu_fixture.hpp"
#include "reference/embree_tracer.hpp"

namespace {

// Twice the documented offset per unit of reach: the band the module's ray starts may take.
constexpr double kOffsetBand = 2.0 / 8192.0;
constexpr uint32_t kSize = 128;

const TechniqueCase kTechniques[] = {{"izb", shadows::Technique::Izb, 1, false},
                                     {"izb+csm", shadows::Technique::Izb, 1, true},
                                     {"izb 32 spp", shadows::Technique::Izb, 32, false},
                                     {"rt", shadows::Technique::RayTraced, 1, false},
                                     {"rt 32 spp", shadows::Technique::RayTraced, 32, false}};

struct NamedLight {
  std::string name;
  shadows::Light module;     // scene space, as set_light takes it
  reference::TrueLight truth;  // the tracer's coordinates
};

reference::PinholeCamera camera_of(engine::Renderer& renderer) {
  const engine::FrameView& view = renderer.frame_view();
  reference::PinholeCamera camera;
  camera.eye = glm::dvec3(view.camera_position);
  camera.inv_view_proj = glm::inverse(glm::dmat4(view.projection) * glm::dmat4(view.view));
  camera.width = renderer.extent().width;
  camera.height = renderer.extent().height;
  return camera;
}

// The scene's sun and every spot and point light, each placed by its Transform (a spot shines down its
// -Z); the truth's positions rebased by `shift` as the tracer's triangles are.
std::vector<NamedLight> lights_of(engine::Scene& scene, const glm::dvec3& shift) {
  std::vector<NamedLight> out;
  engine::Registry& r = scene.registry;
  NamedLight sun{"sun", {}, {}};
  const glm::vec3 d = glm::normalize(r.get<engine::DirectionalLight>(scene.light).direction);
  for (int k = 0; k < 3; ++k) sun.module.direction[k] = d[k];
  sun.truth.direction = glm::dvec3(d);
  out.push_back(sun);
  const auto place = [&](engine::Entity e, shadows::LightType type, float range) {
    const glm::dmat4 world(r.get<engine::Transform>(e).world);
    NamedLight l{r.get<engine::Name>(e).value, support::local_light_at(glm::mat4(world), type, range).module, {}};
    l.truth.sun = false;
    l.truth.position = glm::dvec3(world[3]) + shift;
    l.truth.range = range;
    l.truth.spot_direction = -glm::dvec3(world[2]);
    return l;
  };
  r.each<engine::SpotLight>([&](engine::Entity e, engine::SpotLight& s) {
    NamedLight l = place(e, shadows::LightType::Spot, s.range);
    l.module.inner_cone = s.inner_cone;
    l.module.outer_cone = s.outer_cone;
    l.truth.spot = true;
    l.truth.outer_cone = s.outer_cone;
    out.push_back(l);
  });
  r.each<engine::PointLight>([&](engine::Entity e, engine::PointLight& p) {
    out.push_back(place(e, shadows::LightType::Point, p.range));
  });
  return out;
}

struct Tally {
  size_t covered = 0;
  size_t other_surface = 0;  // silhouettes: the raster and the ray show different surfaces
  size_t compared = 0;
  size_t outside = 0;        // the module's answer outside the true bounds
  double excess = 0.0;       // the mean distance from the module's answer to the bounds
  size_t lit = 0, shadowed = 0;
};

Tally compare(const std::vector<float>& visibility, const std::vector<reference::TrueVisibility>& truth,
              const reference::ShadingPoints& points) {
  Tally t;
  for (size_t i = 0; i < truth.size(); ++i) {
    const reference::TrueVisibility& v = truth[i];
    if (!v.covered() || !points.covered(i)) continue;
    ++t.covered;
    const glm::dvec3 drawn(glm::vec3(points.position[i]));
    const double reach = std::max({std::abs(v.point.x), std::abs(v.point.y), std::abs(v.point.z)}) +
                         glm::length(v.point - glm::dvec3(points.eye));
    if (glm::length(drawn - v.point) > 1.0e-3 * reach) {
      ++t.other_surface;
      continue;
    }
    ++t.compared;
    t.lit += v.lit_min >= 1.0f;
    t.shadowed += v.lit_max <= 0.0f;
    const float excess = std::max({v.lit_min - visibility[i], visibility[i] - v.lit_max, 0.0f});
    t.outside += excess > 1.0e-6f;
    t.excess += excess;
  }
  t.excess /= double(std::max<size_t>(t.compared, 1));
  return t;
}

class IndependentReferenceTest : public GpuTest, public ::testing::WithParamInterface<std::pair<std::string, size_t>> {};

TEST_P(IndependentReferenceTest, EveryLightOfEveryTechniqueIsWithinTheTrueBounds) {
  const auto& [scene_name, view] = GetParam();
  auto& r = make_renderer(scene_name, view, kSize, kSize);
  // Shading points on the triangles themselves: the smooth terminator lifts them off their facets by
  // design (MaterialsTest checks it), which this reference, working from the triangles, does not model.
  r.set_smooth_terminator(false);
  shadows::Settings base;
  base.izb.resolution = 512;
  base.izb.trace = shadows::PassBackend::Compute;
  base.izb.csm_backend = shadows::PassBackend::Compute;
  auto module = shadows::install(r, base);
  r.render_frame(0.0f);
  const reference::EmbreeTracer tracer(scene_->registry, support::frame_shift(r));
  const reference::PinholeCamera camera = camera_of(r);
  const std::vector<NamedLight> lights = lights_of(*scene_, tracer.shift());
  std::vector<reference::TrueVisibility> truth[2];
  for (const NamedLight& light : lights) {
    SCOPED_TRACE(light.name);
    module->set_light(light.module);
    truth[0] = tracer.independent_visibility(camera, light.truth, 1, kOffsetBand);
    truth[1] = tracer.independent_visibility(camera, light.truth, 32, kOffsetBand);
    for (const TechniqueCase& t : kTechniques) {
      SCOPED_TRACE(t.name);
      if (!module->supported(t.technique, nullptr)) continue;  // rt: a ray tracing device only
      module->settings() = t.applied_to(base);
      for (int f = 0; f < t.frames(); ++f) r.render_frame(0.0f);
      const reference::ShadingPoints points = support::capture_shading_points(r);
      const Tally tally = compare(module->read_visibility(), truth[t.spp == 32 ? 1 : 0], points);
      std::printf("%-8s %-18s %-11s covered %6zu other surface %4zu compared %6zu (lit %6zu shadowed %6zu) outside %4zu, by %.2e\n",
                  scene_name.c_str(), light.name.c_str(), t.name, tally.covered, tally.other_surface, tally.compared,
                  tally.lit, tally.shadowed, tally.outside, tally.excess);
      // 1 spp: every pixel within its bounds. 32 spp: the suite's coverage bound (a local light's
      // samples, placed in its perspective light space, flip a sample on a few edge pixels).
      if (t.spp == 1) {
        EXPECT_EQ(tally.outside, 0u);
      } else {
        EXPECT_LE(tally.excess, 1.0e-3);
      }
      EXPECT_LE(tally.other_surface, tally.covered / 50);
      EXPECT_GT(tally.lit, 100u);
      if (light.name == "sun") {
        EXPECT_GT(tally.shadowed, 100u);
      }
    }
  }
  r.finish_frames();
  module.reset();
}

INSTANTIATE_TEST_SUITE_P(Scenes, IndependentReferenceTest,
                         ::testing::Values(std::make_pair(std::string("contact"), size_t(1)),
                                           std::make_pair(std::string("hall"), size_t(1))),
                         [](const auto& info) { return info.param.first + "_view" + std::to_string(info.param.second); });

}  // namespace
