// The receiver flag (engine::ShadowCaster::receives_shadow, the module's receiver mask): a surface that
// does not receive shadows is lit wherever it faces the light, in every technique, while it still casts.
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "frame_capture.hpp"
#include "gpu_fixture.hpp"

namespace {

TEST_F(GpuTest, SurfacesThatReceiveNoShadowAreLitInEveryTechnique) {
  auto& r = make_renderer("contact", 1, 128, 128);
  shadows::Settings base;
  base.izb.resolution = 256;
  auto module = shadows::install(r, base);
  std::vector<std::pair<std::string, engine::ShadowCaster*>> casters;
  scene_->registry.each<engine::Name, engine::ShadowCaster>(
      [&](engine::Entity, engine::Name& name, engine::ShadowCaster& c) { casters.emplace_back(name.value, &c); });
  ASSERT_GT(casters.size(), 2u);
  const TechniqueCase techniques[] = {{"izb", shadows::Technique::Izb, 1, false},
                                  {"izb+csm", shadows::Technique::Izb, 1, true},
                                  {"izb 32 spp", shadows::Technique::Izb, 32, false},
                                  {"sm", shadows::Technique::ShadowMap, 1, false},
                                  {"cascades", shadows::Technique::Cascades, 1, false},
                                  {"hybrid", shadows::Technique::Hybrid, 1, false},
                                  {"rt", shadows::Technique::RayTraced, 1, false}};
  // Who receives: everything; everything but the ground; the ground alone.
  enum { kAll, kGroundOff, kGroundOnly, kCases };
  const char* case_names[kCases] = {"all receive", "ground off", "ground alone"};
  for (const TechniqueCase& t : techniques) {
    SCOPED_TRACE(t.name);
    if (!module->supported(t.technique, nullptr)) continue;  // rt: a ray tracing device only
    module->settings() = t.applied_to(base);
    // Facing pixels in shadow (visibility < 1): on the ground, and elsewhere.
    size_t ground[kCases] = {}, others[kCases] = {};
    for (int c = 0; c < kCases; ++c) {
      for (auto& [name, caster] : casters)
        caster->receives_shadow = c == kAll || (c == kGroundOff) == (name != "ground");
      for (int f = 0; f < t.frames(); ++f) r.render_frame(0.0f);
      const std::vector<float> visibility = module->read_visibility();
      const reference::ShadingPoints points = support::capture_shading_points(r);
      const glm::vec3 to_sun = -r.frame_view().light_direction;
      for (size_t i = 0; i < visibility.size(); ++i) {
        if (!points.covered(i) || !points.faces(i, to_sun) || visibility[i] >= 1.0f) continue;
        const bool on_ground = std::abs(points.position[i].y) < 1.0e-3f && points.normal[i].y > 0.99f;
        ++(on_ground ? ground : others)[c];
      }
      std::printf("%-11s %-13s shadowed: ground %4zu, elsewhere %4zu\n", t.name, case_names[c], ground[c], others[c]);
    }
    EXPECT_GT(ground[kAll], 100u);
    EXPECT_EQ(ground[kGroundOff], 0u);
    EXPECT_EQ(others[kGroundOnly], 0u);
    // What does receive keeps its shadows: the flag takes nothing from what the others cast.
    EXPECT_NEAR(double(ground[kGroundOnly]), double(ground[kAll]), 0.02 * double(ground[kAll]));
    EXPECT_NEAR(double(others[kGroundOff]), double(others[kAll]), 0.02 * double(others[kAll]) + 2.0);
  }
  for (auto& [name, caster] : casters) caster->receives_shadow = true;
  r.finish_frames();
  module.reset();
}

}  // namespace
