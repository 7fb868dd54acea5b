// Skinned and morphing casters (glTF skins and morph targets, deformed by skinning.comp before the
// G-buffer and handed to the module as DeformedPositions): at ten animation times each, every
// technique matches Embree traced against the same pose deformed on the CPU, within the bounds the
// static scenes keep; the shadow differs between times; frames run three in flight, so the
// deformation of one frame overlaps the previous frames' reads of the same vertices (the `syncval`
// label runs this under synchronization validation).
#include <array>
#include <filesystem>

#include "animated_gltf.hpp"
#include "engine/core/skinning.hpp"
#include <shared/shadow_common.h>
#include "frame_capture.hpp"
#include "penumbra_mask.hpp"
#include "gpu_fixture.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace {

constexpr uint32_t kSize = 160;
constexpr uint32_t kFramesInFlight = 3;
constexpr int kTimes = 10;

struct AnimatedCase {
  const char* name;
  std::string (*write)(const std::filesystem::path& dir);
  float duration;  // seconds the clip's ten times spread over
};

void PrintTo(const AnimatedCase& c, std::ostream* os) { *os << c.name; }

// Records frames without waiting for each: frame N waits only for frame N - kFramesInFlight, as a
// windowed renderer does.
class InFlightFrames {
 public:
  InFlightFrames(engine::gpu::Context& ctx, engine::Renderer& renderer) : ctx_(ctx), renderer_(renderer) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = ctx.command_pool();
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = kFramesInFlight;
    VK_CHECK(vkAllocateCommandBuffers(ctx.device(), &alloc, cmds_.data()));
    VkFenceCreateInfo info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    info.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    for (VkFence& f : fences_) VK_CHECK(vkCreateFence(ctx.device(), &info, ctx.allocator(), &f));
  }
  ~InFlightFrames() {
    finish();
    for (VkFence f : fences_) vkDestroyFence(ctx_.device(), f, ctx_.allocator());
    vkFreeCommandBuffers(ctx_.device(), ctx_.command_pool(), kFramesInFlight, cmds_.data());
  }
  void submit() {
    const size_t slot = next_ % kFramesInFlight;
    VK_CHECK(vkWaitForFences(ctx_.device(), 1, &fences_[slot], VK_TRUE, UINT64_MAX));
    if (renderer_.frames_pending() >= kFramesInFlight) renderer_.after_frame();
    renderer_.update(0.0f);
    VkCommandBuffer cmd = cmds_[slot];
    VK_CHECK(vkResetCommandBuffer(cmd, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(vkBeginCommandBuffer(cmd, &begin));
    renderer_.record(cmd);
    VK_CHECK(vkEndCommandBuffer(cmd));
    VK_CHECK(vkResetFences(ctx_.device(), 1, &fences_[slot]));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    VK_CHECK(vkQueueSubmit(ctx_.queue(), 1, &submit, fences_[slot]));
    ++next_;
  }
  void finish() {
    VK_CHECK(vkWaitForFences(ctx_.device(), kFramesInFlight, fences_.data(), VK_TRUE, UINT64_MAX));
    renderer_.finish_frames();
  }

 private:
  engine::gpu::Context& ctx_;
  engine::Renderer& renderer_;
  std::array<VkCommandBuffer, kFramesInFlight> cmds_{};
  std::array<VkFence, kFramesInFlight> fences_{};
  uint64_t next_ = 0;
};

class AnimatedCastersTest : public GpuTest, public testing::WithParamInterface<AnimatedCase> {
 protected:
  void TearDown() override {
    module_.reset();
    GpuTest::TearDown();
  }
  // Poses the scene's clips at `seconds`; then two frames at earlier poses and the checked one at
  // this pose, all three in flight before the last is waited for.
  void render_at(InFlightFrames& frames, float seconds) {
    for (float earlier : {seconds - 0.2f, seconds - 0.1f, seconds}) {
      engine::update_clip_animations(scene_->registry, earlier);
      frames.submit();
    }
    frames.finish();
  }
  // The hybrid's sharp points (as IzbTest.HybridKeepsTheExactTermWherePenumbraeAreUnderAPixel: those no
  // penumbra of a pixel's width or more reaches) match Embree within the IZB's bound.
  void check_hybrid_near_points(InFlightFrames& frames, float seconds) {
    const shadows::Settings saved = module_->settings();
    shadows::Settings& hybrid = module_->settings();
    hybrid.technique = shadows::Technique::Hybrid;
    hybrid.izb.samples_per_pixel = 1;
    hybrid.izb.csm = false;
    render_at(frames, seconds);
    const auto visibility = module_->read_visibility();
    const auto points = support::capture_shading_points(*renderer_);
    const engine::FrameView& view = renderer_->frame_view();
    reference::EmbreeTracer tracer(scene_->registry, support::frame_shift(*renderer_));
    const auto truth = support::reference_visibility(*renderer_, tracer, 1);
    const auto sharp = support::sub_pixel_penumbra_mask(
        points, truth, tracer, -view.light_direction, std::tan(0.5f * glm::radians(view.light_angular_diameter_degrees)),
        2.0f * std::tan(0.5f * view.vertical_fov) / float(points.height));
    size_t near = 0, mismatched = 0;
    for (size_t i = 0; i < visibility.size(); ++i) {
      if (!sharp[i]) continue;
      ++near;
      mismatched += (visibility[i] < 0.5f) != (truth[i] < 0.5f);
    }
    std::printf("hybrid at %.2f s: %zu near points, %zu mismatched\n", seconds, near, mismatched);
    EXPECT_GT(near, size_t(kSize * kSize / 8)) << "hybrid at " << seconds << " s: too few near points";
    EXPECT_LE(double(mismatched), 0.0002 * double(near)) << "hybrid at " << seconds << " s: " << mismatched << " of " << near;
    module_->settings() = saved;
  }
  std::shared_ptr<shadows::ShadowModule> module_;
};

struct TechniqueBound {
  TechniqueCase technique;
  double max_mismatch;  // 1 spp: of the covered pixels
  double max_coverage_mae;
};

TEST_P(AnimatedCastersTest, EveryTechniqueMatchesTheReferenceAtTenTimes) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "animated_casters";
  std::filesystem::create_directories(dir);
  const std::string file = GetParam().write(dir);
  scene_ = engine::load_scene(file);
  scene_->apply_view(0);
  ASSERT_GT(scene_->registry.count<engine::AnimationPlayer>(), 0u) << file << " has no animation";
  renderer_ = std::make_unique<engine::Renderer>(*ctx_, VkExtent2D{kSize, kSize}, kFramesInFlight);
  renderer_->set_scene(*scene_);
  ASSERT_FALSE(renderer_->geometry()->deformed().empty()) << "nothing was deformed";
  // The static suites' bounds: the IZB exact (1 spp mismatch 2e-4, 32 spp coverage MAE 1e-3); the
  // shadow map aliases, bounded as in the static scenes by what it measures (4x, with a floor).
  const std::vector<TechniqueBound> techniques = {
      {{"izb", shadows::Technique::Izb, 1, false}, 0.0002, 0.0},
      {{"izb+csm", shadows::Technique::Izb, 1, true}, 0.0002, 0.0},
      {{"izb32", shadows::Technique::Izb, 32, false}, 1.0, 1.0e-3},
      {{"sm", shadows::Technique::ShadowMap, 1, false}, 0.01, 0.0},
  };
  shadows::Settings base;
  base.izb.resolution = 512;
  module_ = shadows::install(*renderer_, base);
  InFlightFrames frames(*ctx_, *renderer_);
  std::vector<std::vector<float>> izb_terms;
  for (int k = 0; k < kTimes; ++k) {
    const float t = GetParam().duration * float(k) / float(kTimes);
    for (const TechniqueBound& tb : techniques) {
      module_->settings() = tb.technique.applied_to(base);
      for (int f = 0; f < tb.technique.frames(); ++f) render_at(frames, t);
      const auto visibility = module_->read_visibility();
      reference::EmbreeTracer tracer(scene_->registry, support::frame_shift(*renderer_));
      const auto truth = support::reference_visibility(*renderer_, tracer, tb.technique.spp);
      const auto cmp = reference::compare_visibility(visibility, truth);
      EXPECT_GT(cmp.pixels, kSize * kSize / 4);
      if (tb.technique.spp == 1) {
        EXPECT_LE(cmp.mismatch_rate, tb.max_mismatch)
            << tb.technique.name << " at " << t << " s: " << cmp.mismatched << " of " << cmp.pixels;
      } else {
        EXPECT_LE(cmp.coverage_mae, tb.max_coverage_mae) << tb.technique.name << " at " << t << " s";
      }
      if (std::string(tb.technique.name) == "izb") izb_terms.push_back(visibility);
      if (std::string(tb.technique.name) == "izb") check_hybrid_near_points(frames, t);
      std::printf("%s t=%.2f %s: mismatch %.6f (%llu of %llu), coverage MAE %.6f\n", GetParam().name, t,
                  tb.technique.name, cmp.mismatch_rate, (unsigned long long)cmp.mismatched,
                  (unsigned long long)cmp.pixels, cmp.coverage_mae);
    }
  }
  EXPECT_EQ(izb_terms.size(), size_t(kTimes));
  // The shadow moves: every time differs from the one before it.
  for (size_t k = 1; k < izb_terms.size(); ++k) {
    size_t changed = 0;
    for (size_t i = 0; i < izb_terms[k].size(); ++i) changed += izb_terms[k][i] != izb_terms[k - 1][i];
    EXPECT_GT(changed, 5u) << "time " << k << " casts the same shadow as time " << k - 1;
    std::printf("%s: time %zu changes %zu pixels of the shadow\n", GetParam().name, k, changed);
  }
}

INSTANTIATE_TEST_SUITE_P(Clips, AnimatedCastersTest,
                         testing::Values(AnimatedCase{"skinned_cylinder", &support::write_bending_cylinder_gltf, 2.0f},
                                         AnimatedCase{"morph_flap", &support::write_morph_gltf, 2.0f}),
                         [](const testing::TestParamInfo<AnimatedCase>& info) { return std::string(info.param.name); });

}  // namespace
