// Moving casters and a moving sun (scene-file animations, as in the walkthrough): every frame, the
// IZB with the CSM prepass must still match Embree traced against that frame's geometry, and the
// shadows must actually change between frames.
#include <cmath>

#include "engine/core/animation.hpp"
#include "frame_capture.hpp"
#include "gpu_fixture.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace {

constexpr uint32_t kWidth = 128, kHeight = 96;

struct Case {
  const char* file;  // under content/
  size_t view;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.file << " view " << c.view; }

class DynamicSceneTest : public GpuTest, public testing::WithParamInterface<Case> {
 protected:
  void TearDown() override {
    module_.reset();
    GpuTest::TearDown();
  }
  std::shared_ptr<shadows::ShadowModule> module_;
};

TEST_P(DynamicSceneTest, HardShadowsMatchReferenceWhileCastersAndSunMove) {
  auto& r = make_renderer(std::string(ENGINE_SOURCE_DIR) + "/content/" + GetParam().file, GetParam().view, kWidth,
                          kHeight);
  ASSERT_GT(scene_->registry.count<engine::Animated>(), 0u) << "the scene has no moving casters";
  shadows::Settings s;
  s.technique = shadows::Technique::Izb;
  s.izb.resolution = 512;
  s.izb.csm = true;
  module_ = shadows::install(r, s);
  auto& light = scene_->registry.get<engine::DirectionalLight>(scene_->light);
  const glm::vec3 noon = light.direction;
  std::vector<float> previous;
  size_t changed[3] = {0, 0, 0};  // pixels whose visibility changed since the previous frame
  for (int frame = 0; frame < 3; ++frame) {
    // Frames 0 -> 1: only the casters move. Frame 2: the sun also turns 20 degrees and sinks a little.
    const float t = 0.9f * float(frame);
    engine::update_animations(scene_->registry, t);
    const float a = frame == 2 ? glm::radians(20.0f) : 0.0f;
    light.direction = glm::normalize(glm::vec3(noon.x * std::cos(a) - noon.z * std::sin(a),
                                               noon.y * (frame == 2 ? 0.85f : 1.0f),
                                               noon.x * std::sin(a) + noon.z * std::cos(a)));
    r.render_frame(0.0f);
    const auto visibility = module_->read_visibility();
    reference::EmbreeTracer tracer(scene_->registry);
    const auto ref = support::reference_visibility(r, tracer, 1);
    const auto cmp = reference::compare_visibility(visibility, ref);
    EXPECT_GT(cmp.pixels, kWidth * kHeight / 4) << "frame " << frame;
    EXPECT_LE(cmp.mismatch_rate, 0.0005) << "frame " << frame << ": " << cmp.mismatched << " of " << cmp.pixels;
    if (frame > 0)
      for (size_t i = 0; i < visibility.size(); ++i)
        changed[frame] += (visibility[i] >= 0.0f) && (visibility[i] != previous[i]);
    previous = visibility;
  }
  EXPECT_GT(changed[1], 10u) << "moving casters did not move their shadows";
  EXPECT_GT(changed[2], 10u) << "the shadows did not follow the sun";
}

INSTANTIATE_TEST_SUITE_P(Levels, DynamicSceneTest,
                         testing::Values(Case{"test_levels/wall.json", 0}, Case{"levels/courtyard.json", 0}),
                         [](const testing::TestParamInfo<Case>& info) {
                           return std::string(info.index == 0 ? "wall" : "courtyard");
                         });

}  // namespace
