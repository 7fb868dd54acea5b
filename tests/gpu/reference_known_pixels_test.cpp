// The Embree reference on the contact scene, checked at pixels whose answer is known analytically.
#include <cmath>

#include "engine/assets/procedural_scenes.hpp"
#include "frame_capture.hpp"
#include "gpu_fixture.hpp"

namespace {

using namespace engine::procedural;

// The pixel whose centre sees world point `p` (and that point is what the pixel shows).
glm::ivec2 pixel_of(const engine::FrameView& view, const glm::vec3& p) {
  const glm::vec4 clip = view.view_projection * glm::vec4(p, 1.0f);
  const glm::vec2 ndc = glm::vec2(clip) / clip.w;
  return glm::ivec2(glm::floor((ndc * 0.5f + 0.5f) * glm::vec2(view.extent.width, view.extent.height)));
}

TEST_F(GpuTest, ReferenceAgreesWithAnalyticAnswersOnContact) {
  auto& r = make_renderer("contact", 0, 256, 256);
  auto shadows_module = shadows::install(r, [] {
    shadows::Settings s;
    s.technique = shadows::Technique::Izb;
    s.izb.resolution = 512;
    return s;
  }());
  r.render_frame();
  reference::EmbreeTracer tracer(scene_->registry);
  const auto points = support::capture_shading_points(r);
  const glm::vec3 light = r.frame_view().light_direction;
  ASSERT_NEAR(glm::length(light - glm::normalize(contact::kLightDirection)), 0.0f, 1e-5f);
  const auto reference = tracer.visibility_1spp(points, light);
  const auto izb = shadows_module->read_visibility();

  // Under the floating plate: its centre, carried along the light down to the ground.
  const float to_ground = contact::kPlateCenter.y / -light.y;
  const glm::vec3 under_plate = contact::kPlateCenter + light * to_ground;
  // Open ground: in front of the objects, nothing between it and the sun (which comes from +x,+z above).
  const glm::vec3 open_ground{2.0f, 0.0f, 6.0f};
  // The top of the box: nothing is above it.
  const glm::vec3 box_top = contact::kBoxCenter + glm::vec3(0.0f, contact::kBoxHalfSize, 0.0f);

  struct Expectation {
    const char* what;
    glm::vec3 point;
    float visibility;
  };
  for (const Expectation& e : {Expectation{"under the plate", under_plate, 0.0f},
                               Expectation{"open ground", open_ground, 1.0f},
                               Expectation{"box top", box_top, 1.0f}}) {
    const glm::ivec2 px = pixel_of(r.frame_view(), e.point);
    ASSERT_TRUE(px.x >= 0 && px.y >= 0 && px.x < 256 && px.y < 256) << e.what << " is off screen";
    const size_t i = size_t(px.y) * 256 + px.x;
    // The pixel shows the expected surface point (within a pixel's footprint).
    ASSERT_GT(points.position[i].w, 0.5f) << e.what;
    EXPECT_LT(glm::distance(glm::vec3(points.position[i]), e.point), 0.1f) << e.what;
    EXPECT_EQ(reference[i], e.visibility) << e.what << " (reference)";
    EXPECT_EQ(izb[i], e.visibility) << e.what << " (IZB)";
  }
  // The lit image: the ground under the plate is darker than open ground, with the technique's
  // shadow term and with the reference's fed to lighting instead.
  auto luminance = [&](const std::vector<uint8_t>& rgba, const glm::vec3& p) {
    const glm::ivec2 px = pixel_of(r.frame_view(), p);
    const size_t i = (size_t(px.y) * 256 + px.x) * 4;
    return 0.2126f * rgba[i] + 0.7152f * rgba[i + 1] + 0.0722f * rgba[i + 2];
  };
  const auto lit = r.read_output_rgba8();
  EXPECT_LT(luminance(lit, under_plate) + 40.0f, luminance(lit, open_ground));
  r.set_external_shadow_term(reference);
  r.render_frame();
  const auto from_reference = r.read_output_rgba8();
  EXPECT_EQ(from_reference, lit);  // the IZB and the reference agree on every pixel here
  r.set_external_shadow_term({});
  shadows_module.reset();
}

}  // namespace
