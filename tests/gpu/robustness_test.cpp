// Devices without the optional features (masked in the context), scenes past device limits, the live
// allocation count, and determinism: the same frame twice gives the same visibility, bit for bit.
#include <cstring>
#include <functional>
#include <map>
#include <optional>

#include "frame_capture.hpp"
#include "gpu_fixture.hpp"
#include "gpu/resources.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace {

constexpr uint32_t kSize = 96;
const char* const kScene = "contact";
const std::vector<std::string> kModes = {"sm", "cascades", "izb", "izb+csm", "hybrid"};

shadows::Settings settings_for(const std::string& mode) {
  shadows::Settings base;
  base.izb.resolution = 256;
  base.cascades.map_size = 512;
  base.shadow_map.size = 512;
  auto s = shadows::parse_mode(mode, base);
  if (!s) throw std::invalid_argument("unknown mode " + mode);
  return *s;
}

bool is_exact(const std::string& mode) { return mode == "izb" || mode == "izb+csm"; }

// One frame's visibility, or the error the technique refused with.
struct Outcome {
  std::vector<float> visibility;
  std::vector<float> reference;  // exact modes only
  std::optional<std::string> error;
};

class RobustnessTest : public GpuTest {
 protected:
  void TearDown() override {
    module_.reset();
    GpuTest::TearDown();
  }

  // A fresh validated context on the same device treating `masked` as absent (the old one must be clean).
  void use_context(std::vector<std::string> masked) {
    module_.reset();
    renderer_.reset();
    ASSERT_EQ(ctx_->validation_message_count(), 0u) << "validation messages were raised";
    ctx_.reset();
    ctx_ = std::make_unique<engine::gpu::Context>(
        engine::gpu::ContextOptions{.device = test_device(), .validation = true, .masked_features = std::move(masked)});
  }

  // Renders the scene's view 1 with every caster in the CSM (so the prepass runs wherever it is on).
  engine::Renderer& prepare(const shadows::Settings& settings) {
    module_.reset();
    auto& r = make_renderer(kScene, 1, kSize, kSize);
    scene_->registry.each<engine::ShadowCaster>([](engine::Entity, engine::ShadowCaster& c) { c.csm = engine::CsmChoice::On; });
    module_ = shadows::install(r, settings);
    return r;
  }

  Outcome render(const shadows::Settings& settings, bool with_reference, int frames = 1) {
    Outcome out;
    engine::Renderer* r = nullptr;
    try {
      r = &prepare(settings);
      for (int i = 0; i < frames; ++i) r->render_frame(0.0f);
    } catch (const std::exception& e) {
      out.error = e.what();
      return out;
    }
    out.visibility = module_->read_visibility();
    if (with_reference) {
      reference::EmbreeTracer tracer(scene_->registry);
      out.reference = support::reference_visibility(*r, tracer, settings.izb.samples_per_pixel);
    }
    return out;
  }

  std::shared_ptr<shadows::ShadowModule> module_;
};

// A refusal names the missing feature in one line.
void expect_refusal(const Outcome& o, const std::string& feature_phrase, const std::string& what) {
  ASSERT_TRUE(o.error) << what << " ran although it needs " << feature_phrase;
  EXPECT_NE(o.error->find(feature_phrase), std::string::npos) << what << ": " << *o.error;
  EXPECT_EQ(o.error->find('\n'), std::string::npos) << what << ": " << *o.error;
}

struct MaskCase {
  std::string feature;  // ContextOptions::masked_features name
  std::string phrase;   // how refusals name it
};
void PrintTo(const MaskCase& c, std::ostream* os) { *os << c.feature; }

class MaskedFeatureTest : public RobustnessTest, public testing::WithParamInterface<MaskCase> {
 protected:
  bool device_has(const std::string& feature) const {
    const auto& f = ctx_->features();
    if (feature == "conservative_rasterization") return f.conservative_rasterization;
    if (feature == "geometry_shader") return f.geometry_shader;
    if (feature == "fragment_shader_barycentric") return f.fragment_shader_barycentric;
    return f.subgroup_arithmetic_compute_fragment;
  }
};

// Every technique with the feature masked either gives the unmasked device's visibility exactly (and,
// for the exact techniques, Embree's) through its other path, or refuses in one line naming the feature.
TEST_P(MaskedFeatureTest, EveryTechniqueTakesAnotherPathOrRefuses) {
  // Masking a feature the device lacks changes nothing: both runs would take the same path.
  if (!device_has(GetParam().feature))
    GTEST_SKIP() << ctx_->device_name() << " lacks " << GetParam().feature << ": masked and unmasked runs take one path";
  std::map<std::string, Outcome> unmasked;
  for (const auto& mode : kModes) {
    unmasked[mode] = render(settings_for(mode), false);
    ASSERT_FALSE(unmasked[mode].error) << mode << " fails on the unmasked device: " << *unmasked[mode].error;
  }
  use_context({GetParam().feature});
  size_t refused = 0;
  for (const auto& mode : kModes) {
    SCOPED_TRACE(mode);
    const auto masked = render(settings_for(mode), is_exact(mode));
    if (masked.error) {
      expect_refusal(masked, GetParam().phrase, mode);
      ++refused;
      continue;
    }
    EXPECT_EQ(masked.visibility, unmasked[mode].visibility);
    if (is_exact(mode)) {
      const auto cmp = reference::compare_visibility(masked.visibility, masked.reference);
      EXPECT_GT(cmp.pixels, kSize * kSize / 4);
      EXPECT_LE(cmp.mismatch_rate, 0.0002) << cmp.mismatched << " of " << cmp.pixels << " pixels differ";
    }
  }
  // The subgroup reductions have no other path (the plain shadow map needs none of the four); every
  // other feature has a fallback that the modes' automatic choices take.
  const std::string& feature = GetParam().feature;
  EXPECT_EQ(refused, feature == "subgroup_arithmetic" ? 4u : 0u);
}

// The paths that need the feature, asked for explicitly, refuse in one line naming it.
TEST_P(MaskedFeatureTest, PathsThatNeedTheFeatureRefuseInOneLine) {
  use_context({GetParam().feature});
  const std::string& feature = GetParam().feature;
  std::vector<std::pair<std::string, shadows::Settings>> forced;
  auto izb = settings_for("izb");
  auto izb_csm = settings_for("izb+csm");
  if (feature == "conservative_rasterization") {
    izb.izb.trace = shadows::PassBackend::Raster;
    izb.izb.raster = shadows::ConservativeRaster::Hardware;
    forced.emplace_back("hardware conservative trace", izb);
    izb_csm.izb.csm_test = shadows::CsmTest::InnerHw;
    forced.emplace_back("inner-hw CSM test", izb_csm);
  } else if (feature == "geometry_shader") {
    izb.izb.trace = shadows::PassBackend::Raster;
    izb.izb.raster = shadows::ConservativeRaster::Software;
    forced.emplace_back("software conservative trace", izb);
    if (ctx_->features().conservative_rasterization) {
      // Its fragment shader reads gl_PrimitiveID, which SPIR-V puts under the Geometry capability.
      auto hardware = izb;
      hardware.izb.raster = shadows::ConservativeRaster::Hardware;
      forced.emplace_back("hardware conservative trace", hardware);
    }
    izb_csm.izb.csm_backend = shadows::PassBackend::Raster;
    forced.emplace_back("raster CSM", izb_csm);
  } else if (feature == "fragment_shader_barycentric") {
    izb_csm.izb.csm_test = shadows::CsmTest::BarycentricHw;
    forced.emplace_back("bary-hw CSM test", izb_csm);
  } else {
    forced.emplace_back("cascades", settings_for("cascades"));
    forced.emplace_back("izb", izb);
  }
  for (const auto& [what, settings] : forced) expect_refusal(render(settings, false), GetParam().phrase, what);
}

// A shader that declares the feature's SPIR-V capability is refused when its module is made, in one line
// naming the shader and the feature; one that does not is made (the plain shadow map's resolve without
// subgroup operations). Conservative rasterization is pipeline state, not a capability.
TEST_P(MaskedFeatureTest, ShadersThatDeclareTheFeatureAreRefusedInOneLine) {
  const std::map<std::string, std::string> declaring = {{"geometry_shader", "csm.geom"},
                                                        {"fragment_shader_barycentric", "csm_bary_hw.frag"},
                                                        {"subgroup_arithmetic", "shadow_map_resolve.comp"}};
  const auto shader = declaring.find(GetParam().feature);
  if (shader == declaring.end()) GTEST_SKIP() << GetParam().feature << " is no SPIR-V capability";
  use_context({GetParam().feature});
  prepare(settings_for("sm"));  // the module's shaders are registered with the engine's
  std::string what;
  try {
    engine::gpu::ShaderModule module(*ctx_, shader->second);
  } catch (const engine::gpu::VulkanError& e) {
    what = e.what();
  }
  EXPECT_NE(what.find(shader->second), std::string::npos) << "'" << what << "'";
  EXPECT_NE(what.find(GetParam().phrase), std::string::npos) << "'" << what << "'";
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  EXPECT_NO_THROW(engine::gpu::ShaderModule(*ctx_, "shadow_map_resolve_portable.comp"));
}

INSTANTIATE_TEST_SUITE_P(Features, MaskedFeatureTest,
                         testing::Values(MaskCase{"conservative_rasterization", "conservative_rasterization"},
                                         MaskCase{"geometry_shader", "geometry shaders"},
                                         MaskCase{"fragment_shader_barycentric", "fragment_shader_barycentric"},
                                         MaskCase{"subgroup_arithmetic", "subgroup arithmetic"}),
                         [](const testing::TestParamInfo<MaskCase>& info) { return info.param.feature; });

TEST_F(RobustnessTest, UnknownMaskedFeatureIsRefusedInOneLine) {
  try {
    engine::gpu::Context bad({.device = test_device(), .masked_features = {"tessellation"}});
    FAIL() << "an unknown feature name was accepted";
  } catch (const engine::gpu::VulkanError& e) {
    EXPECT_NE(std::string(e.what()).find("'tessellation'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("geometry_shader"), std::string::npos) << e.what();
  }
}

// The same frame twice, and again in a new renderer: the same visibility, bit for bit (the node order
// in the lists and the raster/compute probe's alternation must not show).
TEST_F(RobustnessTest, SameFrameGivesBitIdenticalVisibility) {
  for (const std::string mode : {"izb", "izb+csm", "hybrid"}) {
    SCOPED_TRACE(mode);
    for (uint32_t spp : {1u, 32u}) {
      auto settings = settings_for(mode);
      settings.izb.samples_per_pixel = spp;
      auto& r = prepare(settings);
      std::vector<std::vector<float>> frames;
      for (int i = 0; i < 3; ++i) {
        r.render_frame(0.0f);
        frames.push_back(module_->read_visibility());
      }
      const auto fresh = render(settings, false);
      ASSERT_FALSE(fresh.error) << *fresh.error;
      frames.push_back(fresh.visibility);
      size_t shadowed = 0;
      for (float v : frames[0]) shadowed += v >= 0.0f && v < 1.0f;
      EXPECT_GT(shadowed, 50u) << "spp " << spp << ": too few shadowed pixels to tell";
      for (size_t i = 1; i < frames.size(); ++i) {
        ASSERT_EQ(frames[i].size(), frames[0].size());
        EXPECT_EQ(std::memcmp(frames[i].data(), frames[0].data(), frames[0].size() * sizeof(float)), 0)
            << "spp " << spp << ": frame " << i << " differs from frame 0";
      }
    }
  }
}

// Buffers past the device's storage range or single-allocation size, and images past its largest
// side, are refused before Vulkan sees them: one line naming the resource, no validation message.
TEST_F(RobustnessTest, ResourcesPastDeviceLimitsAreRefusedInOneLine) {
  const auto& limits = ctx_->properties().limits;
  auto expect_error = [](const std::function<void()>& make, const std::string& name) {
    try {
      make();
      ADD_FAILURE() << name << " was created";
    } catch (const engine::gpu::VulkanError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(name), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  const uint32_t before = ctx_->live_allocation_count();
  expect_error([&] {
    engine::gpu::Buffer(*ctx_, VkDeviceSize(limits.maxStorageBufferRange) + 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                        false, "too long storage");
  }, "too long storage");
  if (ctx_->max_memory_allocation_size() < (VkDeviceSize(1) << 32) - 4) {
    expect_error([&] {
      engine::gpu::Buffer(*ctx_, ctx_->max_memory_allocation_size() + 4, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, false,
                          "too large allocation");
    }, "too large allocation");
  }
  expect_error([&] {
    engine::gpu::Image(*ctx_, {limits.maxImageDimension2D + 1, 4}, VK_FORMAT_R8G8B8A8_UNORM,
                       VK_IMAGE_USAGE_SAMPLED_BIT, "too wide image");
  }, "too wide image");
  EXPECT_EQ(ctx_->live_allocation_count(), before);
}

// An IZB node pool beyond the device's storage range: the frame refuses in one line naming the pool
// (no device loss, no validation message), and the next frame with a sane pool renders correctly.
TEST_F(RobustnessTest, NodePoolBeyondTheDeviceIsRefusedInOneLine) {
  auto settings = settings_for("izb");
  settings.izb.node_pool_override = ctx_->properties().limits.maxStorageBufferRange / 8 + 1;
  const auto refused = render(settings, false);
  expect_refusal(refused, "izb nodes", "oversized node pool");
  settings.izb.node_pool_override = 0;
  const auto fine = render(settings, true);
  ASSERT_FALSE(fine.error) << *fine.error;
  EXPECT_LE(reference::compare_visibility(fine.visibility, fine.reference).mismatch_rate, 0.0002);
}

// Every device allocation is counted, and a renderer with its shadow module gives all of its back.
TEST_F(RobustnessTest, LiveAllocationCountReturnsAfterTheRendererGoes) {
  const uint32_t before = ctx_->live_allocation_count();
  const auto o = render(settings_for("hybrid"), false, 2);
  ASSERT_FALSE(o.error) << *o.error;
  EXPECT_GT(ctx_->live_allocation_count(), before + 10);
  module_.reset();
  renderer_.reset();
  EXPECT_EQ(ctx_->live_allocation_count(), before);
}

// The synchronization checks are live where they are asked for (the `syncval` label): two fills of one
// buffer without a barrier between them are a write-after-write hazard the layer must report.
TEST_F(RobustnessTest, SyncValidationReportsAMissingBarrier) {
  if (!ctx_->sync_validation_enabled()) GTEST_SKIP() << "synchronization validation is off (ENGINE_SYNC_VALIDATION)";
  engine::gpu::Buffer target(*ctx_, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, "hazard target");
  ctx_->immediate_submit([&](VkCommandBuffer cmd) {
    vkCmdFillBuffer(cmd, target.handle(), 0, 256, 1u);
    vkCmdFillBuffer(cmd, target.handle(), 0, 256, 2u);
  });
  EXPECT_GT(ctx_->validation_message_count(), 0u) << "the hazard went unreported";
  bool named = false;
  for (const auto& m : ctx_->validation_messages()) named = named || m.find("WRITE_AFTER_WRITE") != std::string::npos;
  EXPECT_TRUE(named);
  ctx_->reset_validation_message_count();
}

}  // namespace
