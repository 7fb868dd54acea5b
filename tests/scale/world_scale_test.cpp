// Exact anywhere: every test scene (and Sponza, where ../shared has it) scaled by {0.01, 1, 100, 1000}
// and moved {0, 1e3, 1e4} units along x and z, plus a centimetre world 1e5 and 1e6 units out through
// the large-world API (engine::Scene::origin: entities kept relative to a double-precision origin),
// each technique compared with Embree from the same shading points. Each configuration must be as
// exact as the same scene at scale 1 at the origin: the IZB's 1 spp mismatch within 0.02 %, izb+csm
// with no false lit pixel, 32 spp coverage MAE within 1e-3, the hybrid's near points within 0.02 %, and
// false-shadowed pixels (acne) no more than at the origin plus 0.01 % of the pixels (for the filtered
// sm and cascades, counted over 2 pixels away from the reference's shadow edges).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "../gpu/gpu_fixture.hpp"
#include "frame_capture.hpp"
#include "penumbra_mask.hpp"
#include "reference/comparator.hpp"
#include "reference/embree_tracer.hpp"
#include "shared/shadow_common.h"

#include <glm/glm.hpp>
#include <glm/gtx/component_wise.hpp>

namespace {

constexpr uint32_t kSize = 160;
constexpr uint32_t kGrid = 256;

struct Placement {
  double scale = 1.0;
  double offset = 0.0;       // along x and z
  bool large_world = false;  // the offset goes into Scene::origin, the entities stay near 0
  std::string label() const {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "scale %g, offset %g%s", scale, offset, large_world ? " (Scene::origin)" : "");
    return buf;
  }
};

// Every placement: the scales {1, 0.01, 100, 1000} at offsets {0, 1e3, 1e4}, and centimetres 1e5 and
// 1e6 units out through Scene::origin. The first is the origin every other is held to.
std::vector<Placement> placements() {
  std::vector<Placement> out;
  for (double scale : {1.0, 0.01, 100.0, 1000.0})
    for (double offset : {0.0, 1.0e3, 1.0e4}) out.push_back({scale, offset, false});
  out.push_back({100.0, 1.0e5, true});
  out.push_back({100.0, 1.0e6, true});
  return out;
}

struct Technique {
  const char* name;
  shadows::Settings settings;
  bool hybrid_near = false;  // compare only the hybrid's near points
};

shadows::Settings base(shadows::Technique technique, uint32_t spp = 1, bool csm = false) {
  shadows::Settings s;
  s.technique = technique;
  s.izb.resolution = kGrid;
  s.izb.samples_per_pixel = spp;
  s.izb.csm = csm;
  // Fixed backends and no lit-culling probe: every frame the same passes.
  s.izb.trace = shadows::PassBackend::Raster;
  s.izb.csm_backend = shadows::PassBackend::Raster;
  s.izb.lit_culling = shadows::LitCulling::Off;
  s.shadow_map.size = 512;
  s.cascades.map_size = 512;
  return s;
}

std::vector<Technique> techniques() {
  return {{"izb", base(shadows::Technique::Izb)},
          {"izb+csm", base(shadows::Technique::Izb, 1, true)},
          {"izb+csm 32spp", base(shadows::Technique::Izb, 32, true)},
          {"sm", base(shadows::Technique::ShadowMap)},
          {"cascades", base(shadows::Technique::Cascades)},
          {"hybrid", base(shadows::Technique::Hybrid), true}};
}

struct Result {
  reference::Comparison cmp;
  reference::Comparison away_from_edges;  // pixels over 2 pixels from a reference shadow edge
  uint64_t near_points = 0;  // hybrid: the points compared
  // Whether float holds the placed scene's shape: its entities' translations (floats, as
  // engine::Transform keeps them) round by at most 1e-4 of its size. Where they round by more (a
  // 0.2-unit scene 1e4 units out: steps of 1e-3), the parts of the scene move against each other, and
  // both the GPU and the reference see that other scene: the exact techniques are held to their bounds
  // there too, the filtered ones, whose aliasing follows the geometry, only where the shape is kept.
  bool shape_kept = true;
};

// The bounds every exact technique keeps anywhere: 1 spp mismatch within 0.02 % (the IZB and the
// hybrid's near points), no false lit pixel with the CSM prepass, 32 spp coverage MAE within 1e-3.
void expect_exact(const Technique& t, const reference::Comparison& c) {
  const std::string name = t.name;
  if (name == "izb" || name == "izb+csm" || t.hybrid_near) {
    EXPECT_LE(c.mismatch_rate, 2.0e-4);
  }
  if (name == "izb+csm") {
    EXPECT_EQ(c.false_lit, 0u);
  }
  if (name == "izb+csm 32spp") {
    EXPECT_LE(c.coverage_mae, 1.0e-3);
  }
}

class WorldScaleTest : public GpuTest, public ::testing::WithParamInterface<std::string> {
 protected:
  void check_placements(std::string scene, const std::vector<Placement>& all);
  // The scene placed as `where`, every technique rendered and compared with Embree.
  std::vector<Result> run(const std::string& scene_name, size_t view, const Placement& where) {
    scene_ = engine::load_scene(scene_name);
    if (where.large_world) {
      engine::transform_scene(*scene_, where.scale, glm::dvec3(0.0), "test");
      scene_->origin = glm::dvec3(where.offset, 0.0, where.offset);
    } else {
      engine::transform_scene(*scene_, where.scale, glm::dvec3(where.offset, 0.0, where.offset), "test");
    }
    scene_->apply_view(view);
    renderer_ = std::make_unique<engine::Renderer>(*ctx_, VkExtent2D{kSize, kSize});
    renderer_->set_scene(*scene_);
    auto module = shadows::install(*renderer_, base(shadows::Technique::Izb));
    // The sun alone (a night scene's moon too), whatever local lights the scene has: HallTest checks those.
    shadows::Light sun;
    const glm::vec3 direction = glm::normalize(scene_->registry.get<engine::DirectionalLight>(scene_->light).direction);
    for (int k = 0; k < 3; ++k) sun.direction[k] = direction[k];
    module->set_light(sun);
    std::unique_ptr<reference::EmbreeTracer> tracer;
    std::vector<float> reference_1spp, reference_32spp;
    std::vector<Result> out;
    const engine::Aabb bounds = scene_->world_bounds();
    const float reach = std::max(glm::compMax(glm::abs(bounds.min)), glm::compMax(glm::abs(bounds.max)));
    const bool shape_kept = std::nextafter(reach, 2.0f * reach) - reach <= 1.0e-4f * glm::compMax(bounds.extent());
    for (const Technique& t : techniques()) {
      module->settings() = t.settings;
      module->settings().units_per_metre = float(scene_->units_per_metre);
      // The automatic CSM choice takes effect on the frame after the one that measured it.
      for (int f = 0; f < (t.settings.izb.csm ? 2 : 1); ++f) renderer_->render_frame(0.0f);
      if (!tracer) tracer = std::make_unique<reference::EmbreeTracer>(scene_->registry, support::frame_shift(*renderer_));
      const uint32_t spp = t.settings.izb.samples_per_pixel;
      std::vector<float>& expected = spp == 32 ? reference_32spp : reference_1spp;
      if (expected.empty()) expected = support::reference_visibility(*renderer_, *tracer, spp);
      const std::vector<float> vis = module->read_visibility();
      Result r;
      r.shape_kept = shape_kept || where.large_world;
      if (!t.hybrid_near) {
        r.cmp = reference::compare_visibility(vis, expected);
        r.away_from_edges = reference::compare_visibility(vis, expected, reference::edge_distance_mask(expected, kSize, kSize, 2.0f));
      } else {
        // The hybrid's sharp points (izb_test's HybridKeepsTheExactTermWherePenumbraeAreUnderAPixel):
        // those no penumbra of a pixel's width or more reaches, where its term is the IZB's.
        const auto points = support::capture_shading_points(*renderer_);
        const engine::FrameView& view = renderer_->frame_view();
        const auto include = support::sub_pixel_penumbra_mask(
            points, expected, *tracer, -view.light_direction,
            std::tan(0.5f * glm::radians(view.light_angular_diameter_degrees)),
            2.0f * std::tan(0.5f * view.vertical_fov) / float(points.height));
        for (uint8_t in : include) r.near_points += in;
        r.cmp = reference::compare_visibility(vis, expected, include);
      }
      std::printf("%-28s %-14s pixels %6llu mismatch %.6f false shadowed %4llu (%4llu off edges) false lit %4llu MAE %.6f%s\n",
                  where.label().c_str(), t.name, (unsigned long long)r.cmp.pixels, r.cmp.mismatch_rate,
                  (unsigned long long)r.cmp.false_shadowed, (unsigned long long)r.away_from_edges.false_shadowed,
                  (unsigned long long)r.cmp.false_lit, r.cmp.coverage_mae, r.shape_kept ? "" : " (shape rounded)");
      out.push_back(r);
    }
    renderer_->finish_frames();
    module.reset();
    renderer_.reset();
    return out;
  }
};

std::string sponza_path() { return std::string(ENGINE_SOURCE_DIR) + "/../shared/content/sponza/sponza.gltf"; }

TEST_P(WorldScaleTest, EveryPlacementIsAsExactAsTheOrigin) { check_placements(GetParam(), placements()); }

void WorldScaleTest::check_placements(std::string scene, const std::vector<Placement>& all) {
  size_t view = 0;
  if (scene == "sponza") {
    if (!std::filesystem::exists(sponza_path())) GTEST_SKIP() << "Sponza is not at " << sponza_path();
    scene = sponza_path();
    view = 1;
  }
  const auto kinds = techniques();
  const std::vector<Result> origin = run(scene, view, all.front());
  for (size_t k = 0; k < kinds.size(); ++k) ASSERT_GT(origin[k].cmp.pixels, 1000u) << kinds[k].name;
  for (const Placement& where : all) {
    SCOPED_TRACE(where.label());
    const std::vector<Result> got = where.scale == 1.0 && where.offset == 0.0 ? origin : run(scene, view, where);
    for (size_t k = 0; k < kinds.size(); ++k) {
      const Technique& t = kinds[k];
      const reference::Comparison& c = got[k].cmp;
      SCOPED_TRACE(t.name);
      // The same shading points, give or take the float rounding of a moved camera (the hybrid compares
      // the pixels its sharp mask keeps, whose count follows the occluders' measured heights: below).
      if (!t.hybrid_near) {
        EXPECT_NEAR(double(c.pixels), double(origin[k].cmp.pixels), 0.01 * double(origin[k].cmp.pixels));
      }
      const double acne_allowance = 1.0e-4 * double(kSize) * double(kSize);  // 0.01 % of the picture
      const std::string name = t.name;
      // Acne: false shadow. The filtered techniques resample a map whose texels fall elsewhere on the
      // scene once it moves, which moves their errors along shadow edges by a few pixels either way;
      // acne shows away from the edges, so they are held to the origin's count there.
      if (name == "sm" || name == "cascades") {
        if (got[k].shape_kept) {
          EXPECT_LE(double(got[k].away_from_edges.false_shadowed),
                    double(origin[k].away_from_edges.false_shadowed) + acne_allowance);
        }
      } else {
        EXPECT_LE(double(c.false_shadowed), double(origin[k].cmp.false_shadowed) + acne_allowance);
      }
      expect_exact(t, c);
      if (t.hybrid_near) {
        EXPECT_GT(got[k].near_points, origin[k].near_points / 2);
      }
      // The filtered techniques keep the error they have at the origin.
      if ((name == "sm" || name == "cascades") && got[k].shape_kept) {
        EXPECT_LE(c.mismatch_rate, origin[k].cmp.mismatch_rate * 1.25 + 2.0e-3);
      }
    }
  }
}

// The room-scale hall (engine "hall": 60 units across, three spot lights 20 to 50 units from what they
// light, a point light and a moon), in metres and in centimetres: every light on its own
// (ShadowModule::set_light), every technique, against Embree toward that light.
class HallTest : public GpuTest {};

struct HallLight {
  std::string name;
  shadows::Light module;            // scene space, as set_light takes it
  reference::LocalLight reference;  // scene space (support::reference_visibility rebases it)
  bool sun = false;
};

std::vector<HallLight> hall_lights(engine::Scene& scene) {
  std::vector<HallLight> out;
  engine::Registry& r = scene.registry;
  HallLight moon{"moon", {}, {}, true};
  const glm::vec3 d = glm::normalize(r.get<engine::DirectionalLight>(scene.light).direction);
  for (int k = 0; k < 3; ++k) moon.module.direction[k] = d[k];
  out.push_back(moon);
  const auto place = [&](engine::Entity e, shadows::LightType type, float range) {
    const support::SceneLight placed = support::local_light_at(r.get<engine::Transform>(e).world, type, range);
    return HallLight{r.get<engine::Name>(e).value, placed.module, placed.reference, false};
  };
  r.each<engine::SpotLight>([&](engine::Entity e, engine::SpotLight& s) {
    HallLight l = place(e, shadows::LightType::Spot, s.range);
    l.module.inner_cone = s.inner_cone;
    l.module.outer_cone = s.outer_cone;
    l.reference.spot = true;
    l.reference.cos_outer = std::cos(s.outer_cone);
    out.push_back(l);
  });
  r.each<engine::PointLight>([&](engine::Entity e, engine::PointLight& p) { out.push_back(place(e, shadows::LightType::Point, p.range)); });
  return out;
}

TEST_F(HallTest, EveryLightOfEveryTechniqueMatchesTheReferenceInMetresAndCentimetres) {
  // Per light and technique: false-shadowed pixels away from the edges in metres, which centimetres
  // must not exceed by more than 0.01 % of the picture.
  std::map<std::string, uint64_t> metre_acne;
  for (const double scale : {1.0, 100.0}) {
    SCOPED_TRACE(testing::Message() << "scale " << scale);
    scene_ = engine::load_scene("hall");
    engine::transform_scene(*scene_, scale, glm::dvec3(0.0), "test");
    scene_->apply_view(1);
    renderer_ = std::make_unique<engine::Renderer>(*ctx_, VkExtent2D{kSize, kSize});
    renderer_->set_scene(*scene_);
    auto module = shadows::install(*renderer_, base(shadows::Technique::Izb));
    reference::EmbreeTracer tracer(scene_->registry, support::frame_shift(*renderer_));
    const auto lights = hall_lights(*scene_);
    ASSERT_EQ(lights.size(), 5u);
    for (const HallLight& light : lights) {
      SCOPED_TRACE(light.name);
      module->set_light(light.module);
      std::vector<float> expected[2];
      for (const Technique& t : techniques()) {
        if (t.hybrid_near && light.sun) continue;  // the sun's hybrid blends in the cascades: the matrix checks its near points
        SCOPED_TRACE(t.name);
        module->settings() = t.settings;
        module->settings().units_per_metre = float(scene_->units_per_metre);
        // A local light's IZB takes the compute trace and CSM (the raster ones are refused for it).
        if (!light.sun) {
          module->settings().izb.trace = shadows::PassBackend::Compute;
          module->settings().izb.csm_backend = shadows::PassBackend::Compute;
        }
        for (int f = 0; f < (t.settings.izb.csm ? 2 : 1); ++f) renderer_->render_frame(0.0f);
        const uint32_t spp = t.settings.izb.samples_per_pixel;
        std::vector<float>& ref = expected[spp == 32 ? 1 : 0];
        if (ref.empty())
          ref = light.sun ? support::reference_visibility(*renderer_, tracer, spp)
                          : support::reference_visibility(*renderer_, tracer, spp, light.reference);
        const auto vis = module->read_visibility();
        const auto c = reference::compare_visibility(vis, ref);
        const auto away = reference::compare_visibility(vis, ref, reference::edge_distance_mask(ref, kSize, kSize, 2.0f));
        std::printf("hall x%-4g %-20s %-14s lit %6zu mismatch %.6f false shadowed %4llu (%4llu off edges) false lit %4llu MAE %.6f\n",
                    scale, light.name.c_str(), t.name, size_t(std::count(ref.begin(), ref.end(), 1.0f)), c.mismatch_rate,
                    (unsigned long long)c.false_shadowed, (unsigned long long)away.false_shadowed,
                    (unsigned long long)c.false_lit, c.coverage_mae);
        const std::string name = t.name;
        EXPECT_GT(c.pixels, 1000u);
        expect_exact(t, c);
        const std::string key = light.name + " " + name;
        if (scale == 1.0) metre_acne[key] = away.false_shadowed;
        else EXPECT_LE(double(away.false_shadowed), double(metre_acne[key]) + 1.0e-4 * kSize * kSize);
      }
    }
    renderer_->finish_frames();
    module.reset();
    renderer_.reset();
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, WorldScaleTest, ::testing::Values("contact", "atrium", "foliage", "canopy", "lamps", "sponza"),
                         [](const auto& info) { return info.param; });

}  // namespace
