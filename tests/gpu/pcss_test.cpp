// PCSS (shaders/shadows/pcss.glsl) in `sm` and `cascades`: the penumbra of a long straight edge runs on
// unbroken across the cascade splits, is as wide as the sun's disc makes it, widens with the
// occluder's height, and a light too small to widen any penumbra past the hard filter changes nothing.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/components.hpp"
#include "gpu_fixture.hpp"

namespace {

constexpr uint32_t kSize = 384;

std::string planks_level() { return std::string(ENGINE_SOURCE_DIR) + "/content/test_levels/planks.json"; }

// A shadow boundary of content/test_levels/planks.json: the line x = `x` on the ground (y = 0), lit on
// its +x side, cast by a plank's edge `height` above the ground, under the level's sun along
// (0.3, -1, 0).
struct Edge {
  float x;
  float height;
};
constexpr float kSunSlope = 0.3f;  // the sun's x travel per unit of descent
constexpr Edge kHighEdge{0.2f + kSunSlope * 6.05f, 6.05f};
constexpr Edge kLowEdge{-2.2f + kSunSlope * 3.05f, 3.05f};

// The radius on the ground, across the edge, of the sun's disc seen past an edge `height` above it,
// for a sun of `degrees` angular diameter: the distance along the light times tan(radius), stretched
// by the sun's slant: height * tan * (1 + slope²).
double penumbra_radius(float height, float degrees) {
  const double tan_half = std::tan(0.5 * double(degrees) * 3.14159265358979 / 180.0);
  return double(height) * tan_half * (1.0 + double(kSunSlope) * kSunSlope);
}

// The width between the 10 % and 90 % lit points of that penumbra: the sun's disc, cut by a straight
// edge, is lit over the fraction of a disc beyond a chord, which crosses 0.1 and 0.9 at 0.687 of the
// radius either side of the hard boundary.
double expected_width(float height, float degrees) { return 2.0 * 0.687 * penumbra_radius(height, degrees); }

struct Capture {
  std::vector<float> term;
  std::vector<glm::vec4> positions;
  glm::vec3 eye{0.0f};
  glm::vec3 forward{0.0f};
};

// The 10 %-90 % width of an edge's penumbra over the ground pixels whose view depth lies in [d0, d1],
// from their world positions: their terms averaged in bins of 5 mm across the edge, smoothed over
// three bins, and the crossings interpolated. Negative where too few pixels lie there.
double penumbra_width(const Capture& c, const Edge& e, float d0, float d1, size_t* samples = nullptr) {
  constexpr float kHalf = 0.5f, kBin = 0.005f;
  constexpr int kBins = int(2.0f * kHalf / kBin);
  std::vector<double> sum(kBins, 0.0), count(kBins, 0.0);
  size_t n = 0;
  for (size_t i = 0; i < c.term.size(); ++i) {
    const glm::vec3 p(c.positions[i]);
    if (c.positions[i].w == 0.0f || std::abs(p.y) > 0.01f) continue;
    const float depth = glm::dot(p - c.eye, c.forward);
    if (depth < d0 || depth > d1) continue;
    const int bin = int(std::floor((p.x - e.x + kHalf) / kBin));
    if (bin < 0 || bin >= kBins) continue;
    sum[bin] += c.term[i];
    count[bin] += 1.0;
    ++n;
  }
  if (samples) *samples = n;
  if (n < 50) return -1.0;
  std::vector<double> profile;
  std::vector<float> x;
  for (int b = 0; b < kBins; ++b) {
    double s = 0.0, w = 0.0;
    for (int k = std::max(b - 1, 0); k <= std::min(b + 1, kBins - 1); ++k) s += sum[k], w += count[k];
    if (w == 0.0) continue;
    profile.push_back(s / w);
    x.push_back(e.x - kHalf + (float(b) + 0.5f) * kBin);
  }
  // The first x past bin `from` where the profile rises through `level`; *at its bin (none: the end).
  auto crossing = [&](double level, size_t from, size_t* at) {
    for (size_t i = std::max<size_t>(from, 1); i < profile.size(); ++i)
      if (profile[i] >= level && profile[i - 1] < level) {
        *at = i;
        const double t = (level - profile[i - 1]) / (profile[i] - profile[i - 1]);
        return double(x[i - 1]) + t * double(x[i] - x[i - 1]);
      }
    *at = profile.size();
    return 0.0;
  };
  size_t at10 = 0, at90 = 0;
  const double x10 = crossing(0.1, 1, &at10);
  const double x90 = crossing(0.9, at10, &at90);
  return at10 == profile.size() || at90 == profile.size() ? -1.0 : x90 - x10;
}

class PcssTest : public GpuTest {
 protected:
  void TearDown() override {
    renderer_.reset();
    module_.reset();  // its GPU objects must go before the device
    GpuTest::TearDown();
  }
  // The level with `settings`, the sun `degrees` wide.
  void setup(const std::string& scene, size_t view, const shadows::Settings& settings, float degrees,
             uint32_t size = kSize) {
    auto& r = make_renderer(scene, view, size, size);
    module_ = shadows::install(r, settings);
    set_sun(degrees);
  }
  void set_sun(float degrees) {
    scene_->registry.get<engine::DirectionalLight>(scene_->light).angular_diameter_degrees = degrees;
  }
  Capture render(int frames = 1) {
    for (int i = 0; i < frames; ++i) renderer_->render_frame(0.0f);
    Capture c;
    c.term = renderer_->read_shadow_term();
    c.positions = renderer_->read_world_positions();
    const engine::FrameView& v = renderer_->frame_view();
    c.eye = v.camera_position;
    c.forward = -glm::vec3(v.view[0][2], v.view[1][2], v.view[2][2]);
    return c;
  }
  std::shared_ptr<shadows::ShadowModule> module_;
};

// Parameterized by a technique that filters with the cascades (cascades; the hybrid's far range).
class PcssSplitTest : public PcssTest, public testing::WithParamInterface<TechniqueCase> {};
// Parameterized by any technique with PCSS.
class PcssHeightTest : public PcssTest, public testing::WithParamInterface<TechniqueCase> {};

}  // namespace

// The high plank's edge runs away from the camera across the first two splits: its penumbra's width
// just before each split's blend band (the nearer cascade alone) and just past the split (the farther
// one alone), and inside the band (both), agree within 20 % and with the sun's geometry.
TEST_P(PcssSplitTest, PenumbraIsContinuousAcrossCascadeSplits) {
  const TechniqueCase& t = GetParam();
  setup(planks_level(), 0, t.applied_to(shadows::Settings{}), 2.0f);
  const Capture c = render(t.frames());
  const shadows::Stats& stats = module_->stats();
  const auto& cascades = module_->settings().cascades;
  ASSERT_EQ(stats.cascade_splits.size(), cascades.count + 1);
  const double expected = expected_width(kHighEdge.height, 2.0f);
  for (size_t k = 1; k <= 2; ++k) {
    const float split = stats.cascade_splits[k];
    const float band_start = split - cascades.blend_band * (split - stats.cascade_splits[k - 1]);
    const float window = 0.12f * split;
    size_t n_before = 0, n_band = 0, n_after = 0;
    const double before = penumbra_width(c, kHighEdge, band_start - window, band_start, &n_before);
    const double band = penumbra_width(c, kHighEdge, band_start, split, &n_band);
    const double after = penumbra_width(c, kHighEdge, split, split + window, &n_after);
    std::printf("[pcss] %s, split %zu at %.2f (band from %.2f): penumbra 10-90 %% width before %.4f (%zu px), in the "
                "band %.4f (%zu px), after %.4f (%zu px); the sun's geometry %.4f\n",
                t.name, k, split, band_start, before, n_before, band, n_band, after, n_after, expected);
    ASSERT_GT(before, 0.0) << "no penumbra measured before split " << k;
    ASSERT_GT(after, 0.0) << "no penumbra measured after split " << k;
    EXPECT_NEAR(after / before, 1.0, 0.2) << "split " << k;
    if (band > 0.0) {
      EXPECT_NEAR(band / before, 1.0, 0.2) << "split " << k;
    }
    for (double w : {before, after}) {
      EXPECT_GT(w, 0.6 * expected) << "split " << k;
      EXPECT_LT(w, 1.6 * expected) << "split " << k;
    }
  }
}

// Two planks, one twice as high as the other: the higher one's penumbra is about twice as wide
// (measured at the same view depths, each near the sun's geometry). The cascades' fixed kernel, the
// narrowest filter, is made narrower than either penumbra.
TEST_P(PcssHeightTest, PenumbraWidensWithOccluderHeight) {
  const TechniqueCase& t = GetParam();
  shadows::Settings settings = t.applied_to(shadows::Settings{});
  settings.cascades.kernel_radius = 0.02f;
  setup(planks_level(), 0, settings, 2.0f);
  const Capture c = render(t.frames());
  const double high = penumbra_width(c, kHighEdge, 3.0f, 6.0f);
  const double low = penumbra_width(c, kLowEdge, 3.0f, 6.0f);
  const double ratio = kHighEdge.height / kLowEdge.height;
  std::printf("[pcss] %s: penumbra 10-90 %% width at view depths 3-6: high plank %.4f (geometry %.4f), low plank "
              "%.4f (geometry %.4f), ratio %.3f (heights %.3f)\n",
              t.name, high, expected_width(kHighEdge.height, 2.0f), low, expected_width(kLowEdge.height, 2.0f),
              high / low, ratio);
  ASSERT_GT(high, 0.0);
  ASSERT_GT(low, 0.0);
  EXPECT_GT(high, low);
  EXPECT_NEAR(high / low, ratio, 0.3 * ratio);
  EXPECT_GT(high, 0.6 * expected_width(kHighEdge.height, 2.0f));
  EXPECT_LT(high, 1.6 * expected_width(kHighEdge.height, 2.0f));
}

// The hybrid filters a penumbra as wide as gpu_shared::kPenumbraMaxRadius pixels at its own width:
// under an 8-degree sun the high plank's penumbra is 26 to 38 pixels in radius at 384x384 (as wide as
// a 4K screen's under the real sun), which a reach of 24 pixels filtered 0.84 as wide.
TEST_F(PcssTest, HybridPenumbraWiderThanTwentyFourPixelsKeepsItsWidth) {
  constexpr float kDegrees = 8.0f;
  setup(planks_level(), 0, TechniqueCase{"hybrid", shadows::Technique::Hybrid, 1, false}.applied_to(shadows::Settings{}),
        kDegrees);
  const Capture c = render();
  const double width = penumbra_width(c, kHighEdge, 4.0f, 6.0f);
  const double expected = expected_width(kHighEdge.height, kDegrees);
  const double pixel_at_6 = 6.0 * 2.0 * std::tan(0.5 * double(renderer_->frame_view().vertical_fov)) / kSize;
  const double radius_pixels = penumbra_radius(kHighEdge.height, kDegrees) / pixel_at_6;
  std::printf("[pcss] hybrid, %g-degree sun: high plank's penumbra 10-90 %% width %.4f at view depths 4-6 "
              "(geometry %.4f; radius %.1f pixels or more, at most 1.5 times that)\n",
              double(kDegrees), width, expected, radius_pixels);
  ASSERT_GT(radius_pixels, 24.0) << "the case must need more than the old reach";
  ASSERT_GT(width, 0.0);
  EXPECT_NEAR(width / expected, 1.0, 0.12);
}

// A sun too small to widen any penumbra past half a texel (sm) or past the cascades' kernel runs the
// PCSS pipelines yet writes the hard path's term bit for bit, with every masking mode; on the planks a
// sun 2 degrees wide does change the term (the PCSS path is live). (On `contact` its casters stand
// too low for 2 degrees to widen a penumbra past those bounds.)
TEST_F(PcssTest, TinyLightGivesTheHardTermBitForBit) {
  struct Case {
    const char* name;
    shadows::Technique technique;
    shadows::Masking masking;
  };
  for (const std::string& scene : {std::string("contact"), planks_level()}) {
    for (const Case& k : {Case{"sm", shadows::Technique::ShadowMap, shadows::Masking::Auto},
                          Case{"cascades off", shadows::Technique::Cascades, shadows::Masking::Off},
                          Case{"cascades edge", shadows::Technique::Cascades, shadows::Masking::Edge},
                          Case{"cascades depth-extent", shadows::Technique::Cascades, shadows::Masking::DepthExtent},
                          Case{"cascades planes", shadows::Technique::Cascades, shadows::Masking::Planes}}) {
      SCOPED_TRACE(scene + ", " + k.name);
      shadows::Settings settings;
      settings.technique = k.technique;
      settings.cascades.map_size = 512;
      settings.cascades.masking = k.masking;
      setup(scene, 0, settings, 0.0f, 192);
      const std::vector<float> hard = render().term;
      set_sun(1.0e-4f);
      const std::vector<float> tiny = render().term;
      set_sun(2.0f);
      const std::vector<float> wide = render().term;
      size_t differ = 0, widened = 0;
      for (size_t i = 0; i < hard.size(); ++i) {
        differ += std::memcmp(&hard[i], &tiny[i], sizeof(float)) != 0;
        widened += hard[i] != wide[i];
      }
      std::printf("[pcss] %s, %s: a sun of 1e-4 degrees changes %zu pixels of %zu, one of 2 degrees %zu\n",
                  scene_->name.c_str(), k.name, differ, hard.size(), widened);
      EXPECT_EQ(differ, 0u);
      if (scene != "contact") {
        EXPECT_GT(widened, hard.size() / 200);
      }
      renderer_.reset();
      module_.reset();
    }
  }
}

// With PCSS the masks are tested over the blocker search's footprint, which holds every PCSS tap:
// as without a light size (CascadesTest.MaskingMatchesUnmaskedAndSavesWork), the depth extent
// reproduces the edge-masked term exactly, edge masking differs from no masking on few pixels and
// never between lit and shadowed, and both still skip work.
TEST_F(PcssTest, MaskingStaysExactWithWidePenumbrae) {
  for (const std::string& scene : {planks_level(), std::string("contact")}) {
    SCOPED_TRACE(scene);
    shadows::Settings settings;
    settings.technique = shadows::Technique::Cascades;
    settings.cascades.map_size = 512;
    setup(scene, 0, settings, scene == "contact" ? 8.0f : 2.0f, 192);
    const shadows::Masking modes[4] = {shadows::Masking::Off, shadows::Masking::Edge, shadows::Masking::DepthExtent,
                                       shadows::Masking::Planes};
    std::vector<float> term[4];
    double fraction[4] = {};
    for (int m = 0; m < 4; ++m) {
      module_->settings().cascades.masking = modes[m];
      term[m] = render().term;
      fraction[m] = module_->stats().expensive_path_fraction;
    }
    size_t edge_diff = 0, extent_diff = 0, flips = 0;
    for (size_t i = 0; i < term[0].size(); ++i) {
      edge_diff += std::abs(term[0][i] - term[1][i]) > 1e-6f;
      extent_diff += term[1][i] != term[2][i];
      flips += (term[0][i] >= 0.5f) != (term[1][i] >= 0.5f);
    }
    std::printf("[pcss] %s masking: expensive off %.4f edge %.4f depth-extent %.4f; edge!=off %zu, extent!=edge %zu, "
                "flips %zu of %zu\n",
                scene_->name.c_str(), fraction[0], fraction[1], fraction[2], edge_diff, extent_diff, flips,
                term[0].size());
    EXPECT_EQ(extent_diff, 0u);
    EXPECT_LT(double(edge_diff), 0.01 * double(term[0].size()));
    EXPECT_EQ(flips, 0u);
    EXPECT_LT(fraction[1], fraction[0]);
    EXPECT_LT(fraction[2], fraction[0]);
    // The plane blocks: every tap of PCSS's searches and filter settled, the unmasked term bit for bit.
    size_t planes_diff = 0;
    for (size_t i = 0; i < term[0].size(); ++i) planes_diff += std::memcmp(&term[0][i], &term[3][i], sizeof(float)) != 0;
    std::printf("[pcss] %s masking: planes expensive %.4f, planes!=off %zu\n", scene_->name.c_str(), fraction[3], planes_diff);
    EXPECT_EQ(planes_diff, 0u);
    EXPECT_LT(fraction[3], fraction[0]);
    renderer_.reset();
    module_.reset();
  }
}

// A spot light's sphere (Light::radius) in the perspective map of `sm` (and of `cascades`, which
// shadows a spot light with the same map, filtered): a light 12 above the ground, just beside the high
// plank's edge (6 above the ground, halfway down), casts a penumbra on the ground as wide as a disc
// of the radius times (distance from the edge to the ground) / (from the light to the edge) = 1, and a
// radius too small for half a texel changes nothing.
TEST_F(PcssTest, SpotLightRadiusWidensItsPenumbra) {
  constexpr float kRadius = 0.15f;
  // The shadow boundary under the plank's lower right corner (0.2, 6.0) seen from (0.4, 12).
  constexpr Edge kEdge{0.0f, 6.0f};
  for (shadows::Technique technique : {shadows::Technique::ShadowMap, shadows::Technique::Cascades}) {
    shadows::Settings settings;
    settings.technique = technique;
    setup(planks_level(), 0, settings, 0.0f);
    shadows::Light spot{.type = shadows::LightType::Spot, .direction = {0.0f, -1.0f, 0.0f},
                        .position = {0.4f, 12.0f, 3.5f}, .range = 30.0f, .inner_cone = 0.6f, .outer_cone = 0.8f};
    std::vector<float> terms[3];
    Capture soft;
    for (int k = 0; k < 3; ++k) {
      spot.radius = k == 0 ? 0.0f : k == 1 ? 1.0e-6f : kRadius;
      module_->set_light(spot);
      soft = render();
      terms[k] = soft.term;
    }
    EXPECT_EQ(std::memcmp(terms[0].data(), terms[1].data(), terms[0].size() * sizeof(float)), 0);
    const double width = penumbra_width(soft, kEdge, 3.0f, 6.0f);
    const double expected = 2.0 * 0.687 * kRadius * kEdge.height / (12.0 - kEdge.height);
    std::printf("[pcss] %s, spot light of radius %.2f: penumbra 10-90 %% width %.4f (geometry %.4f)\n",
                technique == shadows::Technique::ShadowMap ? "sm" : "cascades", kRadius, width, expected);
    EXPECT_GT(width, 0.6 * expected);
    EXPECT_LT(width, 1.6 * expected);
    renderer_.reset();
    module_.reset();
  }
}

// `sm`'s masking (ShadowMapSettings::masking) skips the PCSS taps of the pixels its depth blocks
// settle and gives the term of the unmasked resolve bit for bit, under suns of two sizes on two
// scenes (on a CPU device in its split form: a listing pass, then the listed pixels' taps). The
// resolve's counts show the taps it skipped. A spot or point light's map is not masked.
TEST_F(PcssTest, ShadowMapMaskingGivesTheUnmaskedTermBitForBit) {
  struct Case {
    std::string scene;
    size_t view;
    float sun_degrees;
  };
  const std::vector<Case> cases = {
      {"contact", 0, 0.53f}, {"contact", 1, 2.0f}, {planks_level(), 0, 0.53f}, {planks_level(), 0, 2.0f}};
  // On a CPU device, its split resolve and a GPU's resolve in one pass (SHADOWS_GPU_PATHS).
  const bool cpu = ctx_->properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  for (int gpu_paths = 0; gpu_paths < (cpu ? 2 : 1); ++gpu_paths)
  for (const Case& k : cases) {
    shadows::Settings settings;
    settings.technique = shadows::Technique::ShadowMap;
    if (gpu_paths) setenv("SHADOWS_GPU_PATHS", "1", 1);
    setup(k.scene, k.view, settings, k.sun_degrees, 256);
    unsetenv("SHADOWS_GPU_PATHS");  // read when the module was created
    SCOPED_TRACE(scene_->name + " view " + std::to_string(k.view) + (gpu_paths ? ", GPU paths" : ""));
    std::vector<float> term[2];
    double fraction[2] = {};
    for (int masked = 0; masked < 2; ++masked) {
      module_->settings().shadow_map.masking = masked == 1;
      term[masked] = render().term;
      fraction[masked] = module_->stats().expensive_path_fraction;
    }
    size_t differ = 0;
    for (size_t i = 0; i < term[0].size(); ++i) differ += std::memcmp(&term[0][i], &term[1][i], sizeof(float)) != 0;
    std::printf("[pcss] sm masking%s, %s view %zu, sun %.2f degrees: taps ran on %.4f of the pixels (%.4f unmasked), "
                "%zu pixels differ\n",
                gpu_paths ? " (GPU paths)" : "", scene_->name.c_str(), k.view, k.sun_degrees, fraction[1], fraction[0],
                differ);
    EXPECT_EQ(differ, 0u);
    EXPECT_DOUBLE_EQ(fraction[0], 1.0);
    EXPECT_LT(fraction[1], 0.9);
    renderer_.reset();
    module_.reset();
  }
}

INSTANTIATE_TEST_SUITE_P(Techniques, PcssSplitTest,
                         testing::Values(TechniqueCase{"cascades", shadows::Technique::Cascades, 1, false}),
                         [](const testing::TestParamInfo<TechniqueCase>& info) { return std::string(info.param.name); });
INSTANTIATE_TEST_SUITE_P(Techniques, PcssHeightTest,
                         testing::Values(TechniqueCase{"sm", shadows::Technique::ShadowMap, 1, false},
                                         TechniqueCase{"cascades", shadows::Technique::Cascades, 1, false}),
                         [](const testing::TestParamInfo<TechniqueCase>& info) { return std::string(info.param.name); });
