// The frustum-traced IZB and the CSM z-prepass against the Embree reference, on lavapipe (CTest) or the
// device ENGINE_DEVICE names; the hardware paths run where the device has them and skip naming what it lacks.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <tuple>

#include <shared/shadow_common.h>

#include "frame_capture.hpp"
#include "gpu_fixture.hpp"
#include "penumbra_mask.hpp"
#include "csm_pass.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace {

constexpr uint32_t kSize = 128;
constexpr uint32_t kGrid = 256;
// 32 spp coverage tests at 256^2: at 128^2 a 0.02 % bound is two pixels, one sample's rounding apart.
constexpr uint32_t kCoverageSize = 256;

struct Rendered {
  std::vector<float> visibility;
  std::vector<float> reference;
  shadows::Stats stats;
};

class IzbTest : public GpuTest {
 protected:
  // Renders `scene` at `view` with `settings` (two frames: the second sees a grown pool if any)
  // and, when asked, the reference for the same shading points.
  Rendered render(const std::string& scene, size_t view, shadows::Settings settings, bool with_reference = true,
                  int frames = 1, uint32_t size = kSize) {
    auto& r = make_renderer(scene, view, size, size);
    module_ = shadows::install(r, settings);
    // The automatic CSM choice counts from the frame after the one that measured it on the GPU (one
    // more would skip a CSM whose yield was under 1%, as contact's is).
    if (settings.izb.csm) frames += 1;
    for (int i = 0; i < frames; ++i) r.render_frame(0.0f);
    Rendered out;
    out.visibility = module_->read_visibility();
    out.stats = module_->stats();
    if (with_reference) {
      reference::EmbreeTracer tracer(scene_->registry);
      out.reference = support::reference_visibility(r, tracer, settings.izb.samples_per_pixel);
    }
    return out;
  }

  static shadows::Settings izb(uint32_t spp, bool csm = false, shadows::CsmTest test = shadows::CsmTest::Barycentric) {
    shadows::Settings s;
    s.technique = shadows::Technique::Izb;
    s.izb.resolution = kGrid;
    s.izb.samples_per_pixel = spp;
    s.izb.csm = csm;
    s.izb.csm_test = test;
    // The lit map where a test asks for it: its automatic choice times frames, so counts would vary.
    s.izb.lit_culling = shadows::LitCulling::Off;
    return s;
  }

  // Renders `frames` frames of `scene` view 0 with `settings`, each expected to match `expected`, and
  // checks that the probe whose choice `which` names timed both of its ways (`ways`), each seen in
  // some frame, and kept one by measurement. The module stays installed for further checks.
  void expect_probe_times_both(const std::string& scene, const shadows::Settings& settings,
                               const std::vector<float>& expected, int frames,
                               shadows::Stats::BackendChoice shadows::Stats::*which,
                               std::array<const char*, 2> ways) {
    auto& r = make_renderer(scene, 0, kSize, kSize);
    module_ = shadows::install(r, settings);
    std::vector<std::string> seen;
    for (int i = 0; i < frames; ++i) {
      r.render_frame(0.0f);
      EXPECT_EQ(module_->read_visibility(), expected) << "frame " << i;
      seen.push_back((module_->stats().*which).backend);
    }
    const auto& choice = module_->stats().*which;
    EXPECT_EQ(choice.reason.rfind("auto: ", 0), 0u) << choice.reason;
    EXPECT_TRUE(choice.backend == ways[0] || choice.backend == ways[1]) << choice.backend;
    EXPECT_GT(choice.raster_ms, 0.0) << ways[0];
    EXPECT_GT(choice.compute_ms, 0.0) << ways[1];
    for (const char* way : ways) EXPECT_NE(std::find(seen.begin(), seen.end(), way), seen.end()) << way;
  }

  void expect_fit_holds_candidates(const std::string& scene, size_t view, uint32_t width, uint32_t height,
                                   uint32_t resolution);

  void TearDown() override {
    module_.reset();  // before the context goes
    GpuTest::TearDown();
  }

  std::shared_ptr<shadows::ShadowModule> module_;
};

struct SceneView {
  std::string scene;
  size_t view;
  // Floors, about half of what lavapipe gives, so a path that loses most of its work fails: pixels of
  // fractional 32 spp coverage, and candidates the CSM culls with the Hertel and with the barycentric
  // test (each; 0 where no CSM caster shadows anything in view).
  uint64_t min_fractional = 0;
  uint64_t min_culled = 0;
};
void PrintTo(const SceneView& v, std::ostream* os) { *os << v.scene << " view " << v.view; }
std::string name_of(const testing::TestParamInfo<SceneView>& info) {
  return info.param.scene + "_view" + std::to_string(info.param.view);
}

class IzbSceneTest : public IzbTest, public testing::WithParamInterface<SceneView> {};

TEST_P(IzbSceneTest, OneSampleMatchesReference) {
  const auto r = render(GetParam().scene, GetParam().view, izb(1));
  const auto cmp = reference::compare_visibility(r.visibility, r.reference);
  EXPECT_GT(cmp.pixels, kSize * kSize / 4);
  EXPECT_LE(cmp.mismatch_rate, 0.0002) << cmp.mismatched << " of " << cmp.pixels << " pixels differ";
  EXPECT_GT(r.stats.nodes_inserted, 0u);
  EXPECT_EQ(r.stats.node_overflow, 0u);
}

// The reference takes the same μQuad samples, so the coverage is all but exact (measured: MAE and
// mismatch <= 1.6e-4); a path collapsed to the pixel centre is over these bounds on every view, and has
// no fractional pixels at all.
TEST_P(IzbSceneTest, ThirtyTwoSamplesMatchReferenceCoverage) {
  const auto r = render(GetParam().scene, GetParam().view, izb(32), true, 1, kCoverageSize);
  const auto cmp = reference::compare_visibility(r.visibility, r.reference);
  EXPECT_LE(cmp.coverage_mae, 1.0e-3);
  EXPECT_LE(cmp.mismatch_rate, 0.0002) << cmp.mismatched << " of " << cmp.pixels << " pixels differ";
  uint64_t fractional = 0, reference_fractional = 0;
  for (size_t i = 0; i < r.visibility.size(); ++i) {
    fractional += r.visibility[i] > 0.0f && r.visibility[i] < 1.0f;
    reference_fractional += r.reference[i] > 0.0f && r.reference[i] < 1.0f;
  }
  std::printf("32 spp: coverage MAE %.2e, mismatch %.2e, %llu fractional pixels (reference %llu)\n", cmp.coverage_mae,
              cmp.mismatch_rate, (unsigned long long)fractional, (unsigned long long)reference_fractional);
  EXPECT_GE(fractional, GetParam().min_fractional) << "too few pixels of fractional coverage";
}

// The CSM may only cull points that are truly shadowed, so visibility is the plain IZB's exactly; and
// it must cull, where the scene has CSM casters in view (a CSM that writes nothing passes the rest).
TEST_P(IzbSceneTest, CsmCullingIsConservativeForEveryAvailableTest) {
  const auto plain = render(GetParam().scene, GetParam().view, izb(1));
  double hertel_rate = -1, bary_rate = -1;
  uint64_t hertel_culled = 0, bary_culled = 0;
  for (auto test : {shadows::CsmTest::Hertel, shadows::CsmTest::Barycentric}) {
    const auto culled = render(GetParam().scene, GetParam().view, izb(1, true, test), false);
    const auto cmp = reference::compare_visibility(culled.visibility, plain.reference);
    EXPECT_EQ(cmp.false_shadowed, 0u) << shadows::csm_test_name(test);
    EXPECT_EQ(culled.visibility, plain.visibility) << shadows::csm_test_name(test);
    EXPECT_LE(culled.stats.nodes_inserted, plain.stats.nodes_inserted);
    EXPECT_GE(culled.stats.csm_culled, GetParam().min_culled) << shadows::csm_test_name(test) << " culled too little";
    std::printf("%s: culled %llu, rate %.4f\n", shadows::csm_test_name(test).c_str(),
                (unsigned long long)culled.stats.csm_culled, culled.stats.culling_rate);
    (test == shadows::CsmTest::Hertel ? hertel_rate : bary_rate) = culled.stats.culling_rate;
    (test == shadows::CsmTest::Hertel ? hertel_culled : bary_culled) = culled.stats.csm_culled;
  }
  // Four corners inside is a weaker demand than the circle test: an order that means something only
  // where both culled.
  if (hertel_culled > 0 && bary_culled > 0) {
    EXPECT_GE(bary_rate, hertel_rate);
  }
}

// The hardware coverage tests (fragment-shader barycentrics, inner conservative rasterization) where
// the device has them: as conservative as the others, and culling as much as the barycentric floor.
class IzbHardwareCsmTest : public IzbTest,
                           public testing::WithParamInterface<std::tuple<SceneView, shadows::CsmTest>> {};

TEST_P(IzbHardwareCsmTest, CullingIsConservative) {
  const auto& [sv, test] = GetParam();
  {
    auto& r = make_renderer(sv.scene, sv.view, kSize, kSize);
    auto probe = shadows::install(r, izb(1));
    if (std::string why; !probe->supported(test, &why)) GTEST_SKIP() << shadows::csm_test_name(test) << ": " << why;
  }
  const auto plain = render(sv.scene, sv.view, izb(1));
  const auto culled = render(sv.scene, sv.view, izb(1, true, test), false);
  const auto cmp = reference::compare_visibility(culled.visibility, plain.reference);
  EXPECT_EQ(cmp.false_shadowed, 0u);
  EXPECT_EQ(culled.visibility, plain.visibility);
  EXPECT_LE(culled.stats.nodes_inserted, plain.stats.nodes_inserted);
  if (sv.min_culled > 0) {
    EXPECT_GT(culled.stats.csm_culled, 0u) << "culled nothing";
  }
}

// The compute trace and compute CSM against the raster ones: identical visibility, bit for bit, at 1
// and 32 samples per pixel, without the CSM and with each test that has both passes (every caster in
// the CSM, so it runs on every view); and in the hybrid, which also reads the trace's occluder distance.
TEST_P(IzbSceneTest, ComputeAndRasterPassesAgreeBitForBit) {
  using shadows::PassBackend;
  auto visibility = [&](shadows::Settings s, PassBackend trace, PassBackend csm) {
    s.izb.trace = trace;
    s.izb.csm_backend = csm;
    auto& r = make_renderer(GetParam().scene, GetParam().view, kSize, kSize);
    scene_->registry.each<engine::ShadowCaster>([](engine::Entity, engine::ShadowCaster& c) { c.csm = engine::CsmChoice::On; });
    module_ = shadows::install(r, s);
    r.render_frame(0.0f);
    EXPECT_EQ(module_->stats().trace_choice.backend, shadows::backend_name(trace));
    if (s.izb.csm) {
      EXPECT_EQ(module_->stats().csm_status, "ran");
    }
    auto v = module_->read_visibility();
    module_.reset();
    return v;
  };
  for (uint32_t spp : {1u, 32u}) {
    const auto raster = visibility(izb(spp), PassBackend::Raster, PassBackend::Raster);
    EXPECT_EQ(visibility(izb(spp), PassBackend::Compute, PassBackend::Raster), raster) << spp << " spp";
    for (auto test : {shadows::CsmTest::Hertel, shadows::CsmTest::Barycentric}) {
      const auto csm_raster = visibility(izb(spp, true, test), PassBackend::Raster, PassBackend::Raster);
      EXPECT_EQ(visibility(izb(spp, true, test), PassBackend::Compute, PassBackend::Compute), csm_raster)
          << shadows::csm_test_name(test) << " " << spp << " spp";
    }
  }
  // The hybrid's penumbrae too, at 32 spp as well: each pixel's occluder height is the nearest of all
  // its occluders, whatever order the trace tests them in.
  for (uint32_t spp : {1u, 32u}) {
    auto hybrid = izb(spp, true);
    hybrid.technique = shadows::Technique::Hybrid;
    EXPECT_EQ(visibility(hybrid, PassBackend::Compute, PassBackend::Compute),
              visibility(hybrid, PassBackend::Raster, PassBackend::Raster))
        << "hybrid+csm " << spp << " spp";
  }
}

// Anchored nodes (32 spp, compute trace) change which lists hold a pixel, never a verdict: every
// node test covers all of a pixel's samples, and the trace pairs each caster with every anchor whose
// 2x2 block it touches. Linked and sorted lists (whose scatter makes the build's anchors again), with
// and without the CSM (whose settled samples need no node), at 128x128 pixels and at 32x32, where a
// pixel's samples spread over more texels than the build's 4x4 window holds (node_texels' list);
// each size takes each layout once and the CSM once.
TEST_P(IzbSceneTest, AnchoredNodesChangeNoVerdictAndTakeFewerNodes) {
  using shadows::ListLayout;
  struct Case {
    uint32_t size;
    bool csm;
    ListLayout lists;
  };
  uint64_t fewer = 0;
  for (const Case& c : {Case{kSize, false, ListLayout::Linked}, Case{kSize, true, ListLayout::Sorted},
                        Case{32u, false, ListLayout::Sorted}, Case{32u, true, ListLayout::Linked}}) {
    auto every_texel = izb(32, c.csm);
    every_texel.izb.trace = shadows::PassBackend::Compute;
    every_texel.izb.lists = c.lists;
    every_texel.izb.anchored_nodes = false;
    auto anchored = every_texel;
    anchored.izb.anchored_nodes = true;
    const auto a = render(GetParam().scene, GetParam().view, every_texel, false, 1, c.size);
    const auto b = render(GetParam().scene, GetParam().view, anchored, false, 1, c.size);
    const std::string what = std::to_string(c.size) + "² csm " + (c.csm ? "on" : "off") + " " +
                             shadows::list_layout_name(c.lists);
    EXPECT_EQ(b.visibility, a.visibility) << what;
    EXPECT_LE(b.stats.nodes_inserted, a.stats.nodes_inserted) << what;
    EXPECT_EQ(b.stats.node_overflow, 0u) << what;
    fewer += a.stats.nodes_inserted - std::min(a.stats.nodes_inserted, b.stats.nodes_inserted);
    std::printf("%s v%zu %s: nodes %llu -> %llu, pairs %llu -> %llu, tests %llu -> %llu\n", GetParam().scene.c_str(),
                GetParam().view, what.c_str(), (unsigned long long)a.stats.nodes_inserted,
                (unsigned long long)b.stats.nodes_inserted, (unsigned long long)a.stats.trace_fragments_after_cull,
                (unsigned long long)b.stats.trace_fragments_after_cull, (unsigned long long)a.stats.triangle_tests,
                (unsigned long long)b.stats.triangle_tests);
  }
  EXPECT_GT(fewer, 0u);
}

std::string hardware_csm_name(const testing::TestParamInfo<IzbHardwareCsmTest::ParamType>& info) {
  std::string name = std::get<0>(info.param).scene + "_view" + std::to_string(std::get<0>(info.param).view) + "_" +
                     shadows::csm_test_name(std::get<1>(info.param));
  for (char& c : name) c = c == '-' ? '_' : c;
  return name;
}
// Seen on lavapipe (fractional pixels at 256^2; culled by hertel/bary at 128^2): contact 258, 221 (84/86,
// 47/52), atrium 652, 274 (13434/13437, 1080/1081), foliage 3622, 3177, canopy 3438 (none culled on these:
// their leaves are alpha-tested or left out of the CSM by the automatic choice, and nothing else in the
// CSM is shadowed).
const SceneView kSceneViews[] = {{"contact", 0, 130, 40},   {"contact", 1, 110, 20}, {"atrium", 0, 320, 6000},
                                 {"atrium", 1, 135, 500},   {"foliage", 0, 1800, 0}, {"foliage", 1, 1600, 0},
                                 {"canopy", 1, 1700, 0}};
INSTANTIATE_TEST_SUITE_P(Scenes, IzbSceneTest, testing::ValuesIn(kSceneViews), name_of);
INSTANTIATE_TEST_SUITE_P(Scenes, IzbHardwareCsmTest,
                         testing::Combine(testing::ValuesIn(kSceneViews),
                                          testing::Values(shadows::CsmTest::BarycentricHw, shadows::CsmTest::InnerHw)),
                         hardware_csm_name);

// The hardware conservative trace (VK_EXT_conservative_rasterization), where the device has it:
// against Embree at 1 and 32 samples per pixel, with the bounds of the default path.
TEST_P(IzbSceneTest, HardwareConservativeTraceMatchesReference) {
  if (!ctx_->features().conservative_rasterization)
    GTEST_SKIP() << ctx_->device_name() << " lacks VK_EXT_conservative_rasterization";
  if (!ctx_->features().geometry_shader)
    GTEST_SKIP() << ctx_->device_name() << " lacks geometry shaders (the trace reads gl_PrimitiveID)";
  for (uint32_t spp : {1u, 32u}) {
    auto s = izb(spp);
    s.izb.trace = shadows::PassBackend::Raster;
    s.izb.raster = shadows::ConservativeRaster::Hardware;
    const auto r = render(GetParam().scene, GetParam().view, s, true, 1, spp == 32 ? kCoverageSize : kSize);
    const auto cmp = reference::compare_visibility(r.visibility, r.reference);
    EXPECT_TRUE(r.stats.hardware_conservative);
    EXPECT_LE(cmp.mismatch_rate, 0.0002) << spp << " spp: " << cmp.mismatched << " of " << cmp.pixels;
    if (spp == 32) {
      EXPECT_LE(cmp.coverage_mae, 1.0e-3);
    }
    EXPECT_GT(r.stats.nodes_inserted, 0u);
  }
}

// Known-lit culling is exact: with it on, izb, izb+csm and the hybrid give the same visibility bit for
// bit at 1 and 32 spp, and it turns no point Embree sees shadowed lit. Prints the culled share.
TEST_P(IzbSceneTest, LitCullingIsExact) {
  for (uint32_t spp : {1u, 32u}) {
    auto plain_izb = izb(spp);
    auto with_csm = izb(spp, true);
    auto hybrid = izb(spp, true);
    hybrid.technique = shadows::Technique::Hybrid;
    hybrid.izb.resolution = kGrid;
    std::vector<float> reference;
    for (const auto& [name, base] : {std::pair<const char*, shadows::Settings>{"izb", plain_izb}, {"izb+csm", with_csm},
                                     {"hybrid+csm", hybrid}}) {
      auto off = base;
      off.izb.lit_culling = shadows::LitCulling::Off;
      auto on = base;
      on.izb.lit_culling = shadows::LitCulling::On;
      const auto a = render(GetParam().scene, GetParam().view, off, reference.empty());
      if (reference.empty()) reference = a.reference;
      const auto b = render(GetParam().scene, GetParam().view, on, false);
      EXPECT_EQ(b.visibility, a.visibility) << name << " " << spp << " spp";
      if (base.technique == shadows::Technique::Izb && !base.izb.csm) {
        // Sorted lists place nodes after the build: a culled pixel must get none there either.
        auto sorted = on;
        sorted.izb.lists = shadows::ListLayout::Sorted;
        const auto c = render(GetParam().scene, GetParam().view, sorted, false);
        EXPECT_EQ(c.visibility, a.visibility) << name << " sorted lists " << spp << " spp";
        EXPECT_EQ(c.stats.nodes_inserted, b.stats.nodes_inserted) << name << " sorted lists " << spp << " spp";
      }
      EXPECT_EQ(a.stats.lit_culled, 0u);
      // A culled pixel is one node fewer at 1 spp (the CSM culls only other pixels); at 32 spp one or more.
      if (spp == 1) {
        EXPECT_EQ(b.stats.nodes_inserted + b.stats.lit_culled, a.stats.nodes_inserted) << name;
      } else {
        EXPECT_LE(b.stats.nodes_inserted + b.stats.lit_culled, a.stats.nodes_inserted) << name;
      }
      // No false lit point at 1 spp. At 32 spp a pixel is compared by its coverage at 0.5, where the
      // IZB already differs from Embree by a sample on rare edge pixels (canopy view 1: one pixel), and
      // the hybrid's soft term may rightly be lit under a far occluder: there, exactly as without.
      const auto cmp = reference::compare_visibility(b.visibility, reference);
      const auto today = reference::compare_visibility(a.visibility, reference);
      const bool exact_binary = spp == 1 && base.technique == shadows::Technique::Izb;
      EXPECT_EQ(cmp.false_lit, exact_binary ? 0u : today.false_lit)
          << name << " " << spp << " spp (without lit culling: " << today.false_lit << ")";
      std::printf("%s v%zu %u²/%u² %s %u spp: %.1f%% of lit candidates culled (%llu of %llu), nodes %llu -> %llu\n",
                  GetParam().scene.c_str(), GetParam().view, kSize, kGrid, name, spp,
                  b.stats.lit_candidates ? 100.0 * double(b.stats.lit_culled) / double(b.stats.lit_candidates) : 0.0,
                  (unsigned long long)b.stats.lit_culled, (unsigned long long)b.stats.lit_candidates,
                  (unsigned long long)a.stats.nodes_inserted, (unsigned long long)b.stats.nodes_inserted);
    }
  }
}

// The light frustum's fit places the grid so that every candidate's ray origin (1 spp) or μQuad
// corner (32 spp, where the fit bounds corners made in fast arithmetic, widened past rounding, and
// makes the exact ones near grazing) lies inside it: checked against the corners shadow_common.h makes
// on the CPU, with the same bits as the build's. The fit's border is two texels a side; what the
// widening leaves of it stays over one and a half on the grid's longer side, so the window holds the
// view without wasting texels.
void IzbTest::expect_fit_holds_candidates(const std::string& scene, size_t view, uint32_t width, uint32_t height,
                                          uint32_t resolution) {
  for (uint32_t spp : {1u, 32u}) {
    auto s = izb(spp);
    s.izb.resolution = resolution;
    s.izb.lit_culling = shadows::LitCulling::On;  // read_lit_map reads the frame's grid
    auto& r = make_renderer(scene, view, width, height);
    module_ = shadows::install(r, s);
    r.render_frame(0.0f);
    const glm::mat4 grid = module_->read_lit_map().light_view_projection;
    const auto points = support::capture_shading_points(r);
    const glm::vec2 viewport(float(points.width), float(points.height));
    const float res = float(resolution);
    glm::vec2 lo(1.0e30f), hi(-1.0e30f);
    size_t candidates = 0, grazing = 0, outside = 0;
    for (uint32_t y = 0; y < points.height; ++y) {
      for (uint32_t x = 0; x < points.width; ++x) {
        const size_t i = size_t(y) * points.width + x;
        if (points.position[i].w <= 0.5f || !gpu_shared::faces_light(points.normal[i])) continue;
        const glm::vec3 p(points.position[i]), n(points.normal[i]);
        ++candidates;
        glm::vec3 origins[4];
        int count = 1;
        if (spp == 1) {
          origins[0] = gpu_shared::shadow_ray_origin(p, n, gpu_shared::shadow_ray_offset(p, points.eye));
        } else {
          count = 4;
          bool near_grazing = false;
          for (int k = 0; k < 4; ++k) {
            const glm::vec2 corner(float(x + (k & 1)), float(y + (k >> 1)));
            const auto ray = gpu_shared::pixel_corner_ray(corner, viewport, points.inv_view_proj);
            near_grazing = near_grazing ||
                           std::abs(glm::dot(n, ray.direction)) < glm::length(n) * glm::length(ray.direction) / 16.0f;
            origins[k] = gpu_shared::shadow_ray_origin(gpu_shared::micro_quad_corner_on(ray, p, n), n,
                                                       gpu_shared::shadow_ray_offset(p, points.eye));
          }
          grazing += near_grazing ? 1 : 0;
        }
        for (int k = 0; k < count; ++k) {
          const glm::vec4 clip = grid * glm::vec4(origins[k], 1.0f);
          const glm::vec2 g = (glm::vec2(clip) * 0.5f + 0.5f) * res;
          if (!(g.x >= 0.0f && g.y >= 0.0f && g.x < res && g.y < res) && outside++ < 5)
            ADD_FAILURE() << scene << " spp " << spp << " pixel " << x << "," << y << ": grid " << g.x << "," << g.y;
          lo = glm::min(lo, g);
          hi = glm::max(hi, g);
        }
      }
    }
    ASSERT_GT(candidates, 0u) << scene;
    EXPECT_EQ(outside, 0u) << scene << " spp " << spp;
    const float border = res - std::max(hi.x - lo.x, hi.y - lo.y);
    EXPECT_GE(border, 3.0f) << scene << " spp " << spp << ": the window is wider than the candidates need";
    std::printf("%s view %zu, %ux%u, grid %u, %u spp: %zu candidates (%zu within 1/16 of grazing at some corner), "
                "border %.3f texels\n",
                scene.c_str(), view, width, height, resolution, spp, candidates, grazing, border);
  }
}

TEST_P(IzbSceneTest, FitWindowHoldsEveryCandidate) {
  expect_fit_holds_candidates(GetParam().scene, GetParam().view, kSize, kSize, kGrid);
}

// The same at a size where the grid's texels are finer than the view's pixels: 4K and a 2048 grid on a
// GPU, 640x360 and 1024 on lavapipe.
TEST_F(IzbTest, SponzaFitWindowHoldsEveryCandidate) {
  const std::string path = std::string(ENGINE_SOURCE_DIR) + "/../shared/content/sponza/sponza.gltf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "Sponza not found at " << path;
  const bool cpu = ctx_->device_name().find("llvmpipe") != std::string::npos;
  for (size_t view : {0u, 1u})
    expect_fit_holds_candidates(path, view, cpu ? 640 : 3840, cpu ? 360 : 2160, cpu ? 1024 : 2048);
}

TEST_F(IzbTest, SoftwareConservativeRasterMatchesBruteForce) {
  for (const char* scene : {"foliage", "atrium"}) {
    for (uint32_t spp : {1u, 32u}) {
      auto software = izb(spp);
      software.izb.raster = shadows::ConservativeRaster::Software;
      auto brute = izb(spp);
      brute.izb.brute_force = true;
      // Small: the brute force tests every caster triangle for every pixel.
      const auto a = render(scene, 0, software, false, 1, 48);
      const auto b = render(scene, 0, brute, false, 1, 48);
      EXPECT_EQ(a.visibility, b.visibility) << scene << " spp " << spp;
      EXPECT_GT(a.stats.nodes_inserted, 0u);
      EXPECT_EQ(b.stats.nodes_inserted, 0u);
      EXPECT_GT(b.stats.overflow_pixels, 0u);
    }
  }
}

TEST_F(IzbTest, DepthCullingRemovesFragmentsWithoutChangingTheResult) {
  auto culled = izb(1);
  auto unculled = izb(1);
  unculled.izb.depth_cull = false;
  const auto a = render("atrium", 0, culled, false);
  const auto b = render("atrium", 0, unculled, false);
  EXPECT_EQ(a.visibility, b.visibility);
  EXPECT_GT(a.stats.trace_fragments_before_cull, 0u);
  EXPECT_LT(a.stats.trace_fragments_after_cull, a.stats.trace_fragments_before_cull);
  EXPECT_LT(a.stats.triangle_tests, b.stats.triangle_tests);
}

TEST_F(IzbTest, TinyNodePoolOverflowsIntoTheExactFallback) {
  auto tiny = izb(1);
  tiny.izb.node_pool_override = 64;
  const auto r = render("contact", 0, tiny);
  EXPECT_EQ(r.stats.node_pool_size, 64u);
  EXPECT_GT(r.stats.node_overflow, 0u);
  EXPECT_GT(r.stats.overflow_pixels, 1000u);
  const auto cmp = reference::compare_visibility(r.visibility, r.reference);
  EXPECT_LE(cmp.mismatch_rate, 0.0002);
}

TEST_F(IzbTest, NodePoolGrowsAfterAnOverflow) {
  auto small = izb(32);
  small.izb.node_pool_factor = 0.01f;  // far too small: the first frame overflows
  auto& r = make_renderer("contact", 0, kSize, kSize);
  module_ = shadows::install(r, small);
  r.render_frame(0.0f);
  const auto first = module_->stats();
  r.render_frame(0.0f);
  const auto second = module_->stats();
  EXPECT_GT(first.node_overflow, 0u);
  EXPECT_GT(second.node_pool_size, first.node_pool_size);
  EXPECT_EQ(second.node_overflow, 0u);
}

// Every texel the CSM filled must be fully covered by a caster triangle whose farthest depth over
// the texel is no farther than what was stored (checked in double precision on the CPU).
TEST_F(IzbTest, CsmDepthIsAtLeastTheCoveringTrianglesFarthestDepth) {
  for (auto test : {shadows::CsmTest::Hertel, shadows::CsmTest::Barycentric}) {
    auto& r = make_renderer("atrium", 0, kSize, kSize);
    module_ = shadows::install(r, izb(1, true, test));
    for (int i = 0; i < 3; ++i) r.render_frame(0.0f);  // the automatic choice's measure first
    const auto csm = module_->read_csm();
    ASSERT_EQ(csm.resolution, kGrid);
    // Caster triangles in grid space.
    std::vector<glm::dvec3> tris;
    for (const auto& d : r.draws()) {
      if (d.shadow.csm == engine::CsmChoice::Off) continue;
      const auto& mesh = *scene_->registry.get<engine::Mesh>(d.entity).data;
      for (size_t i = 0; i < mesh.indices.size(); ++i) {
        const glm::dvec4 clip = glm::dmat4(csm.light_view_projection) * glm::dmat4(d.world) *
                                glm::dvec4(glm::dvec3(mesh.vertices[mesh.indices[i]].position), 1.0);
        tris.push_back({(clip.x * 0.5 + 0.5) * kGrid, (clip.y * 0.5 + 0.5) * kGrid, clip.z});
      }
    }
    size_t checked = 0;
    for (uint32_t y = 0; y < kGrid; y += 3) {
      for (uint32_t x = 0; x < kGrid; x += 3) {
        const float stored = csm.depth[size_t(y) * kGrid + x];
        if (stored >= 1.0f) continue;
        double best = 1e30;  // smallest farthest-depth among triangles that fully cover the texel
        for (size_t t = 0; t + 2 < tris.size(); t += 3) {
          const auto &a = tris[t], &b = tris[t + 1], &c = tris[t + 2];
          const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
          if (std::abs(area) < 1e-12) continue;
          bool covers = true;
          double far_depth = -1e30;
          for (int k = 0; k < 4 && covers; ++k) {
            const glm::dvec2 p(x + (k & 1), y + (k >> 1));
            const double w0 = ((c.x - b.x) * (p.y - b.y) - (c.y - b.y) * (p.x - b.x)) / area;
            const double w1 = ((a.x - c.x) * (p.y - c.y) - (a.y - c.y) * (p.x - c.x)) / area;
            const double w2 = 1.0 - w0 - w1;
            covers = w0 >= 0 && w1 >= 0 && w2 >= 0;
            far_depth = std::max(far_depth, w0 * a.z + w1 * b.z + w2 * c.z);
          }
          if (covers) best = std::min(best, far_depth);
        }
        ASSERT_LT(best, 1e29) << "texel " << x << "," << y << " holds a depth but no triangle covers it";
        EXPECT_GE(double(stored), best - 1e-6) << "texel " << x << "," << y;
        ++checked;
      }
    }
    EXPECT_GT(checked, 200u) << shadows::csm_test_name(test);
  }
}

// The lit map against exact geometry (double precision, grid space): for every caster triangle and
// every texel its footprint touches, even at a corner, the map holds a depth no farther than the
// triangle's nearest point over the texel and planes no farther than its plane at the texel's corners,
// or the same over the texel's tile (where the triangle covers a whole tile). The only tolerance is the GPU's float transform into grid
// space (izb_triangles.comp): it moves a vertex's depth by a few units of float rounding, far below
// 1e-6, while the map's own margins (izb_common.glsl) are at least 1e-6; a touch within rounding of a
// texel's border is covered by the map's widened footprint.
TEST_P(IzbSceneTest, LitMapHoldsNoFartherThanEveryTouchingTriangle) {
  const std::string scene = GetParam().scene;
  const size_t view = GetParam().view;
  for (uint32_t spp : {1u, 32u}) {
    auto s = izb(spp);
    s.izb.lit_culling = shadows::LitCulling::On;
    auto& r = make_renderer(scene, view, kSize, kSize);
    module_ = shadows::install(r, s);
    r.render_frame(0.0f);
    const auto map = module_->read_lit_map();
    ASSERT_EQ(map.resolution, kGrid);
    ASSERT_EQ(map.depth.size(), size_t(kGrid) * kGrid);
    ASSERT_EQ(map.corner_depth.size(), size_t(kGrid + 1) * (kGrid + 1));
    ASSERT_EQ(map.tiles_per_side, (kGrid + map.tile - 1) / map.tile);
    ASSERT_EQ(map.tile_depth.size(), size_t(map.tiles_per_side) * map.tiles_per_side);
    ASSERT_EQ(map.tile_corner_depth.size(), size_t(map.tiles_per_side) * map.tiles_per_side * 4);
    // Each tile's least bound, which proves the texel level without the texel's own: no farther than
    // any of its texels' (then every check below of a texel's bound holds for it too).
    ASSERT_EQ(map.tile_least_depth.size(), map.tile_depth.size());
    size_t least_finite = 0;
    for (uint32_t y = 0; y < kGrid; ++y) {
      for (uint32_t x = 0; x < kGrid; ++x) {
        const float least = map.tile_least_depth[size_t(y / map.tile) * map.tiles_per_side + x / map.tile];
        ASSERT_LE(least, map.depth[size_t(y) * kGrid + x]) << scene << " texel " << x << "," << y;
      }
    }
    for (const float least : map.tile_least_depth) least_finite += std::isfinite(least) ? 1 : 0;
    EXPECT_GT(least_finite, 0u) << scene;  // some tile holds a caster at the texel level
    size_t triangles = 0, texels = 0, tile_bounded = 0;
    for (const auto& d : r.draws()) {
      if (!d.shadow.casts_shadow) continue;
      const auto& mesh = *scene_->registry.get<engine::Mesh>(d.entity).data;
      for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
        glm::dvec3 v[3];
        glm::vec2 vf[3];
        for (int k = 0; k < 3; ++k) {
          const glm::dvec4 clip = glm::dmat4(map.light_view_projection) * glm::dmat4(d.world) *
                                  glm::dvec4(glm::dvec3(mesh.vertices[mesh.indices[i + k]].position), 1.0);
          v[k] = {(clip.x * 0.5 + 0.5) * kGrid, (clip.y * 0.5 + 0.5) * kGrid, clip.z};
          vf[k] = glm::vec2(v[k]);
        }
        // Edge-on to the light (the traces' own float test, |area| <= 1e-10): shadows no ray, skipped by
        // every trace.
        const float area_f = (vf[2].x - vf[0].x) * (vf[1].y - vf[0].y) - (vf[2].y - vf[0].y) * (vf[1].x - vf[0].x);
        if (std::abs(area_f) <= 1e-10f) continue;
        ++triangles;
        const int x0 = std::max(0, int(std::floor(std::min({v[0].x, v[1].x, v[2].x}))));
        const int x1 = std::min(int(kGrid) - 1, int(std::floor(std::max({v[0].x, v[1].x, v[2].x}))));
        const int y0 = std::max(0, int(std::floor(std::min({v[0].y, v[1].y, v[2].y}))));
        const int y1 = std::min(int(kGrid) - 1, int(std::floor(std::max({v[0].y, v[1].y, v[2].y}))));
        // The triangle clipped to the closed rectangle [lo, hi] (Sutherland-Hodgman): its nearest depth
        // there (the depth is affine, so its minimum over the intersection lies at a vertex of the
        // clipped polygon), or none where it does not touch it.
        const auto nearest_over = [&](glm::dvec2 lo, glm::dvec2 hi) -> std::optional<double> {
          std::vector<glm::dvec3> poly(v, v + 3);
          for (int edge = 0; edge < 4 && !poly.empty(); ++edge) {
            const int axis = edge & 1;
            const double bound = edge < 2 ? lo[axis] : hi[axis];
            const double sign = edge < 2 ? 1.0 : -1.0;  // keep sign * (p - bound) >= 0
            std::vector<glm::dvec3> out;
            for (size_t k = 0; k < poly.size(); ++k) {
              const glm::dvec3 &p = poly[k], &q = poly[(k + 1) % poly.size()];
              const double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);
              if (dp >= 0) out.push_back(p);
              if ((dp >= 0) != (dq >= 0)) out.push_back(p + (q - p) * (dp / (dp - dq)));
            }
            poly = std::move(out);
          }
          if (poly.empty()) return std::nullopt;
          double nearest = 1e30;
          for (const auto& p : poly) nearest = std::min(nearest, p.z);
          return nearest;
        };
        // Whether a plane bound at grid point `c` is no farther than the triangle's plane there. The
        // plane is extrapolated beyond the triangle, so the GPU's float vertices (a few units of
        // rounding off these) move it by their rounding times the point's barycentric weights.
        const glm::dvec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
        const double twice_area = e1.x * e2.y - e1.y * e2.x;
        const double dzdx = (e1.z * e2.y - e2.z * e1.y) / twice_area;
        const double dzdy = (e2.z * e1.x - e1.z * e2.x) / twice_area;
        const auto plane_bound_holds = [&](float stored, glm::dvec2 c) {
          const double plane = v[0].z + dzdx * (c.x - v[0].x) + dzdy * (c.y - v[0].y);
          double moved = 0.0;
          for (int j = 0; j < 3; ++j) {
            const glm::dvec3 &p = v[(j + 1) % 3], &q = v[(j + 2) % 3];
            const double weight = ((q.x - p.x) * (c.y - p.y) - (q.y - p.y) * (c.x - p.x)) / twice_area;
            const double rounding = 5e-7 * ((std::abs(v[j].x) + std::abs(v[j].y) + 1.0) * (std::abs(dzdx) + std::abs(dzdy)) +
                                            std::abs(v[j].z) + 1.0);
            moved += std::abs(weight) * rounding;
          }
          return double(stored) <= plane + 1e-6 + moved;
        };
        for (int y = y0; y <= y1; ++y) {
          for (int x = x0; x <= x1; ++x) {
            const auto nearest = nearest_over({x, y}, {x + 1, y + 1});
            if (!nearest) continue;
            const size_t t = size_t(y) * kGrid + size_t(x);
            ++texels;
            // The texel's bound and each of its corners' planes, or else the tile's (a triangle that
            // covers a whole tile is bounded there): the lit test asks both levels.
            bool texel_level = double(map.depth[t]) <= *nearest + 1e-6;
            for (int k = 0; k < 4 && texel_level; ++k) {
              const int cx = x + (k & 1), cy = y + (k >> 1);
              texel_level = plane_bound_holds(map.corner_depth[size_t(cy) * (kGrid + 1) + size_t(cx)], {cx, cy});
            }
            if (texel_level) continue;
            const uint32_t tx = uint32_t(x) / map.tile, ty = uint32_t(y) / map.tile;
            const auto corner_point = [&](uint32_t i) { return double(std::min(i * map.tile, kGrid)); };
            const auto tile_nearest = nearest_over({corner_point(tx), corner_point(ty)}, {corner_point(tx + 1), corner_point(ty + 1)});
            bool tile_level = tile_nearest && double(map.tile_depth[size_t(ty) * map.tiles_per_side + tx]) <= *tile_nearest + 1e-6;
            for (uint32_t k = 0; k < 4 && tile_level; ++k) {
              const uint32_t cx = tx + (k & 1), cy = ty + (k >> 1);
              tile_level = plane_bound_holds(map.tile_corner_depth[(size_t(ty) * map.tiles_per_side + tx) * 4 + k],
                                             {corner_point(cx), corner_point(cy)});
            }
            ASSERT_TRUE(tile_level) << scene << " texel " << x << "," << y << ": bounded at neither level";
            ++tile_bounded;
          }
        }
      }
    }
    EXPECT_GT(triangles, 10u) << scene;
    EXPECT_GT(texels, size_t(kGrid)) << scene;
    // The contact floor covers whole tiles: the tile level is used.
    if (scene == "contact") {
      EXPECT_GT(tile_bounded, 0u);
    }
    size_t empty = 0;  // +infinity: no caster touches the texel at the texel level
    for (size_t t = 0; t < map.depth.size(); ++t) empty += std::isinf(map.depth[t]) ? 1 : 0;
    std::printf("%s v%zu %u spp: %zu caster triangles, %zu (triangle, texel) checks, %zu of them at the tile level, "
                "%zu texels empty at the texel level\n",
                scene.c_str(), view, spp, triangles, texels, tile_bounded, empty);
  }
}

// The light frustum walks only the casters near the view: of 225 copies of contact side by side,
// the passes list about one copy's triangles, never fewer than those whose grid bounds (in double
// precision, from the fitted transform) reach the grid, and the answer stays Embree's with the
// compute trace (and the lit map, which reads the same list) and with the raster one, which still
// draws every caster the CPU keeps.
TEST_F(IzbTest, LightFrustumListsOnlyTheCastersNearTheView) {
  for (const auto trace : {shadows::PassBackend::Compute, shadows::PassBackend::Raster}) {
    if (trace == shadows::PassBackend::Raster && !ctx_->features().geometry_shader) continue;
    auto s = izb(1);
    s.izb.trace = trace;
    s.izb.lit_culling = trace == shadows::PassBackend::Compute ? shadows::LitCulling::On : shadows::LitCulling::Off;
    scene_ = engine::load_scene("contact");
    engine::replicate_scene(*scene_, 225);  // more caster draws than one round of the cull's scan (1024)
    scene_->apply_view(0);
    renderer_ = std::make_unique<engine::Renderer>(*ctx_, VkExtent2D{kSize, kSize});
    renderer_->set_scene(*scene_);
    module_ = shadows::install(*renderer_, s);
    renderer_->render_frame(0.0f);
    const auto stats = module_->stats();
    const std::string name = shadows::backend_name(trace);
    reference::EmbreeTracer tracer(scene_->registry);
    const auto cmp = reference::compare_visibility(module_->read_visibility(),
                                                   support::reference_visibility(*renderer_, tracer, 1));
    EXPECT_GT(cmp.pixels, kSize * kSize / 4) << name;
    EXPECT_LE(cmp.mismatch_rate, 0.0002) << name << ": " << cmp.mismatched << " of " << cmp.pixels;
    EXPECT_GT(stats.nodes_inserted, 0u) << name;
    EXPECT_GT(stats.caster_triangles_listed, 0u) << name;
    EXPECT_LT(stats.caster_triangles_listed * 3, stats.caster_triangles) << name;
    std::printf("%s trace: %llu of %llu caster triangles listed\n", name.c_str(),
                (unsigned long long)stats.caster_triangles_listed, (unsigned long long)stats.caster_triangles);
    if (trace != shadows::PassBackend::Compute) continue;
    const auto caster_draws = std::count_if(renderer_->draws().begin(), renderer_->draws().end(),
                                            [](const auto& d) { return d.shadow.casts_shadow; });
    EXPECT_GT(caster_draws, 1024);  // the cull's scan takes several rounds
    const auto map = module_->read_lit_map();
    ASSERT_EQ(map.resolution, kGrid);
    uint64_t reaching = 0;
    for (const auto& d : renderer_->draws()) {
      if (!d.shadow.casts_shadow) continue;
      const auto& mesh = *scene_->registry.get<engine::Mesh>(d.entity).data;
      for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
        glm::dvec2 lo(1e30), hi(-1e30);
        for (int k = 0; k < 3; ++k) {
          const glm::dvec4 clip = glm::dmat4(map.light_view_projection) * glm::dmat4(d.world) *
                                  glm::dvec4(glm::dvec3(mesh.vertices[mesh.indices[i + k]].position), 1.0);
          const glm::dvec2 g = (glm::dvec2(clip) * 0.5 + 0.5) * double(kGrid);
          lo = glm::min(lo, g);
          hi = glm::max(hi, g);
        }
        reaching += hi.x >= 0.0 && hi.y >= 0.0 && lo.x <= kGrid && lo.y <= kGrid;
      }
    }
    EXPECT_GE(stats.caster_triangles_listed, reaching);
  }
}

// The culling culls: on contact view 0 most lit candidates (the floor's open ground, proved lit by
// the floor's own plane at the texel corners) need no node.
TEST_F(IzbTest, LitCullingCullsOnContact) {
  auto on = izb(1);
  on.izb.lit_culling = shadows::LitCulling::On;
  const auto r = render("contact", 0, on, false);
  const auto off = render("contact", 0, izb(1), false);
  EXPECT_GT(r.stats.lit_culled * 2, r.stats.lit_candidates);
  EXPECT_EQ(r.stats.nodes_inserted + r.stats.lit_culled, off.stats.nodes_inserted);
  EXPECT_EQ(r.visibility, off.visibility);
  EXPECT_LT(r.stats.trace_fragments_after_cull + r.stats.triangle_tests,
            off.stats.trace_fragments_after_cull + off.stats.triangle_tests);
}

// LitCulling::Auto times the IZB's passes with the lit map and without once the trace's choice is
// made, keeps one, and says why; the answer is the one without, frame by frame.
TEST_F(IzbTest, AutomaticLitCullingTimesBothAndKeepsOne) {
  auto s = izb(1);
  s.izb.lit_culling = shadows::LitCulling::Auto;
  const auto off = render("contact", 0, izb(1), false);
  // "on": with the lit map (the probe's raster slot), "off": without.
  expect_probe_times_both("contact", s, off.visibility, 32, &shadows::Stats::lit_choice, {"on", "off"});
  EXPECT_EQ(module_->stats().lit_culled > 0, module_->stats().lit_choice.backend == "on");
}

// IzbSettings::csm_timed: the automatic CSM is timed against no prepass and the faster kept, with
// the answer unchanged on every frame; a caster put in the CSM by hand keeps it running untimed.
TEST_F(IzbTest, TimedCsmTimesBothAndKeepsOne) {
  auto plain = izb(1);
  const auto reference = render("atrium", 0, plain, false);
  auto s = izb(1, true);
  s.izb.csm_timed = true;
  expect_probe_times_both("atrium", s, reference.visibility, 32, &shadows::Stats::csm_run_choice, {"run", "skip"});
  const auto& st = module_->stats();
  if (st.csm_run_choice.backend == "skip") {
    EXPECT_EQ(st.csm_status.rfind("skipped: the IZB's passes timed faster", 0), 0u) << st.csm_status;
    EXPECT_EQ(st.csm_culled, 0u);
  } else {
    EXPECT_EQ(st.csm_status, "ran");
    EXPECT_GT(st.csm_culled, 0u);
  }
  module_.reset();

  auto& forced = make_renderer("atrium", 0, kSize, kSize);
  scene_->registry.each<engine::ShadowCaster>([](engine::Entity, engine::ShadowCaster& c) { c.csm = engine::CsmChoice::On; });
  module_ = shadows::install(forced, s);
  for (int i = 0; i < 6; ++i) {
    forced.render_frame(0.0f);
    EXPECT_EQ(module_->stats().csm_status, "ran") << "frame " << i;
  }
  EXPECT_TRUE(module_->stats().csm_run_choice.backend.empty()) << module_->stats().csm_run_choice.backend;
  EXPECT_EQ(module_->read_visibility(), reference.visibility);
}

// On a GPU the compute work's first step is timed in both shapes (izb.h, kIzbStepOne*) and the
// faster kept, with the answer the same in every frame; a CPU device keeps its one shape untimed.
TEST_F(IzbTest, StepOneShapeIsTimedOnAGpu) {
  auto s = izb(1, true);
  s.izb.trace = shadows::PassBackend::Compute;
  s.izb.csm_backend = shadows::PassBackend::Compute;
  const auto first = render("atrium", 0, s, false);
  if (ctx_->properties().deviceType != VK_PHYSICAL_DEVICE_TYPE_CPU) {
    expect_probe_times_both("atrium", s, first.visibility, 24, &shadows::Stats::tile_work_choice, {"wide", "narrow"});
    return;
  }
  auto& r = make_renderer("atrium", 0, kSize, kSize);
  module_ = shadows::install(r, s);
  for (int i = 0; i < 6; ++i) {
    r.render_frame(0.0f);
    EXPECT_EQ(module_->read_visibility(), first.visibility) << "frame " << i;
    EXPECT_TRUE(module_->stats().tile_work_choice.backend.empty()) << module_->stats().tile_work_choice.backend;
  }
}

// Every first-step shape (a GPU's two, forced here so that a CPU device runs them too, and a CPU
// device's own) gives the compute trace, CSM and lit map the same answer, bit for bit, within the
// reference's bound; foliage sends its many small triangles' texels through step 1.
TEST_F(IzbTest, EveryStepOneShapeGivesTheSameAnswer) {
  using shadows::StepOneShape;
  for (const char* scene : {"atrium", "foliage"}) {
    for (uint32_t spp : {1u, 32u}) {
      std::vector<float> first;
      for (const StepOneShape shape : {StepOneShape::Auto, StepOneShape::Wide, StepOneShape::Narrow}) {
        auto s = izb(spp, true);
        s.izb.trace = shadows::PassBackend::Compute;
        s.izb.csm_backend = shadows::PassBackend::Compute;
        s.izb.lit_culling = shadows::LitCulling::On;
        s.izb.step_one_shape = shape;
        const auto r = render(scene, 0, s, first.empty());
        const std::string name = std::string(scene) + " " + std::to_string(spp) + " spp shape " +
                                 std::to_string(int(shape));
        EXPECT_GT(r.stats.trace_pairs, 0u) << name;
        if (first.empty()) {
          const auto cmp = reference::compare_visibility(r.visibility, r.reference);
          EXPECT_LE(cmp.mismatch_rate, 0.0002) << name << ": " << cmp.mismatched << " of " << cmp.pixels;
          first = r.visibility;
        } else {
          EXPECT_EQ(r.visibility, first) << name;
        }
        module_.reset();
      }
    }
  }
}

// IzbSettings::step_timings: the compute work's steps are timed apart only when asked (each
// timestamp waits for the work before it); the pass's own region is there either way. The automatic
// choices show without the statistics.
TEST_F(IzbTest, StepTimingsOnlyWhenAsked) {
  for (bool steps : {false, true}) {
    auto s = izb(1);
    s.izb.trace = shadows::PassBackend::Compute;
    s.izb.step_timings = steps;
    auto& r = make_renderer("contact", 0, kSize, kSize);
    module_ = shadows::install(r, s);
    module_->set_collect_stats(false);
    r.render_frame(0.0f);
    r.render_frame(0.0f);
    const auto times = module_->context().pass_times();
    const auto has = [&](const std::string& name) {
      return std::any_of(times.begin(), times.end(), [&](const auto& t) { return t.name == name; });
    };
    EXPECT_TRUE(has("frustum_trace"));
    for (const char* step : {"light_frustum_fit", "trace_records", "trace_tiles", "trace_texels", "trace_pairs"})
      EXPECT_EQ(has(step), steps) << step;
    // Contact's few caster triangles are set up by the trace's step 1 (no CSM nor lit map reads them
    // before it): no step of their own.
    EXPECT_FALSE(has("light_frustum_triangles"));
    EXPECT_EQ(module_->stats().trace_choice.backend, "compute");
    module_.reset();
  }
}

TEST_F(IzbTest, AutomaticCsmChoiceTakesArchitectureAndLeavesFoliage) {
  for (const char* scene : {"atrium", "foliage"}) {
    auto& r = make_renderer(scene, 0, kSize, kSize);
    module_ = shadows::install(r, izb(1, true));
    // The choice is measured on the GPU and counts from the frame after the one that measured it.
    for (int i = 0; i < 3; ++i) r.render_frame(0.0f);
    const auto& decisions = module_->stats().csm_decisions;
    ASSERT_FALSE(decisions.empty());
    size_t leaves = 0, leaves_in = 0, architecture = 0, architecture_in = 0;
    for (const auto& d : decisions) {
      EXPECT_TRUE(d.automatic);
      EXPECT_FALSE(d.reason.empty());
      if (d.name.rfind("leaves", 0) == 0) {
        ++leaves;
        leaves_in += d.in_csm;
      } else if (d.name == "floor" || d.name.find("wall") != std::string::npos ||
                 d.name.find("roof") != std::string::npos) {
        // The big slabs; thin column shafts may rightly stay out at this grid size.
        ++architecture;
        architecture_in += d.in_csm;
      }
    }
    if (std::string(scene) == "atrium") {
      EXPECT_GT(architecture, 3u);
      EXPECT_EQ(architecture_in, architecture);
    } else {
      EXPECT_GT(leaves, 10u);
      EXPECT_EQ(leaves_in, 0u);
    }
  }
}

// The automatic choice's GPU measure (float) against measure_csm_suitability (the CPU reference) on
// every caster, and "out: measuring" before the first measure has arrived.
TEST_F(IzbTest, AutomaticCsmChoiceGpuMeasureMatchesCpu) {
  for (const char* scene : {"atrium", "foliage"}) {
    auto& r = make_renderer(scene, 0, kSize, kSize);
    module_ = shadows::install(r, izb(1, true));
    r.render_frame(0.0f);
    const auto first = module_->stats().csm_decisions;
    ASSERT_FALSE(first.empty());
    auto alpha_tested = [](const shadows::CsmDecision& d) { return d.reason.find("alpha-tested") != std::string::npos; };
    for (const auto& d : first) {
      if (!alpha_tested(d)) {
        EXPECT_EQ(d.reason.rfind("out: measuring", 0), 0u) << d.name << ": " << d.reason;
      }
    }
    for (int i = 0; i < 2; ++i) r.render_frame(0.0f);
    const glm::vec3 light = glm::normalize(r.frame_view().light_direction);
    size_t compared = 0;
    for (const auto& d : module_->stats().csm_decisions) {
      if (alpha_tested(d)) continue;
      ASSERT_EQ(d.reason.rfind("auto: ", 0), 0u) << d.name << ": " << d.reason;
      // The texel size the module measured against, as its reason prints it (3 digits).
      const size_t at = d.reason.find("texels of ~");
      ASSERT_NE(at, std::string::npos) << d.reason;
      const float texel = std::stof(d.reason.substr(at + 11));
      const engine::Entity e = shadows::entity_of(d);
      const auto* mesh = scene_->registry.try_get<engine::Mesh>(e);
      const auto* transform = scene_->registry.try_get<engine::Transform>(e);
      ASSERT_TRUE(mesh && transform && mesh->data) << d.name;
      std::vector<glm::vec3> positions;
      for (const engine::Vertex& v : mesh->data->vertices) positions.push_back(v.position);
      const auto cpu = shadows::detail::measure_csm_suitability(positions, mesh->data->indices, transform->world, light, texel);
      // Float sums, and the printed texel size's rounding (a relative 5e-4 moves the share by 1e-3 at most).
      EXPECT_NEAR(d.large_triangle_area_share, cpu.coverable_share, 2e-3) << d.name;
      if (std::abs(cpu.coverable_share - shadows::detail::kCsmAutoThreshold) > 2e-3) {
        EXPECT_EQ(d.in_csm, cpu.coverable_share >= shadows::detail::kCsmAutoThreshold) << d.name;
      }
      ++compared;
    }
    EXPECT_GT(compared, 3u);
  }
}

TEST_F(IzbTest, SponzaCsmIsConservative) {
  const std::string path = std::string(ENGINE_SOURCE_DIR) + "/../shared/content/sponza/sponza.gltf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "Sponza not found at " << path;
  uint64_t culled_points = 0;
  for (size_t view : {0u, 1u}) {
    const auto plain = render(path, view, izb(1));
    for (auto test : {shadows::CsmTest::Hertel, shadows::CsmTest::Barycentric}) {
      const auto culled = render(path, view, izb(1, true, test), false);
      const auto cmp = reference::compare_visibility(culled.visibility, plain.reference);
      EXPECT_EQ(cmp.false_shadowed, 0u) << "view " << view;
      EXPECT_EQ(culled.visibility, plain.visibility) << "view " << view;
      culled_points += culled.stats.csm_culled;
    }
    EXPECT_LE(reference::compare_visibility(plain.visibility, plain.reference).mismatch_rate, 0.0002);
  }
  EXPECT_GT(culled_points, 0u);  // view 1 looks into the shaded galleries
}

}  // namespace

namespace {

// Hybrid: hard at contact, soft where the occluder is far above the receiver (a 4-degree sun, so
// that the penumbrae of the pole's top and the plate span pixels at 256x256).
TEST_F(IzbTest, HybridIsHardAtContactAndSoftAway) {
  sun_degrees_ = 4.0f;
  shadows::Settings hybrid;
  hybrid.technique = shadows::Technique::Hybrid;
  hybrid.izb.resolution = 512;
  const auto h = render("contact", 0, hybrid, false, 1, 256);
  const auto positions = renderer_->read_world_positions();
  const auto hard = render("contact", 0, izb(1), false, 1, 256);
  size_t contact_pixels = 0, soft_pixels = 0;
  for (size_t i = 0; i < positions.size(); ++i) {
    if (positions[i].w == 0.0f || hard.visibility[i] != 0.0f) continue;  // shadowed by the IZB only
    const glm::vec3 p(positions[i]);
    if (std::abs(p.y) > 1e-3f) continue;  // on the ground
    const glm::vec2 d = glm::abs(glm::vec2(p.x, p.z)) - glm::vec2(1.0f);  // outside the box footprint by
    const float gap = std::max(d.x, d.y);
    if (gap > 0.0f && gap < 0.1f) {  // right at the box's base: the occluder touches the ground
      ++contact_pixels;
      EXPECT_LT(h.visibility[i], 0.1f) << "pixel " << i;
    }
    if (h.visibility[i] > 0.05f && h.visibility[i] < 0.95f) ++soft_pixels;
  }
  EXPECT_GT(contact_pixels, 5u);
  EXPECT_GT(soft_pixels, 20u);  // the far ends of the pole's and plate's shadows soften
}

// The hybrid keeps the IZB's exact term wherever the sun's penumbrae are narrower than a pixel: with
// the real sun (0.53 degrees) at 256x256, on the pixels no wider penumbra reaches (Embree's nearest
// occluders tell which), the term equals the IZB's bit for bit and matches Embree within the IZB's bound.
TEST_F(IzbTest, HybridKeepsTheExactTermWherePenumbraeAreUnderAPixel) {
  shadows::Settings hybrid;
  hybrid.technique = shadows::Technique::Hybrid;
  hybrid.izb.resolution = 512;
  hybrid.izb.lit_culling = shadows::LitCulling::Off;
  const auto hard = render("contact", 0, izb(1), true, 1, 256);
  const auto h = render("contact", 0, hybrid, true, 1, 256);
  const auto points = support::capture_shading_points(*renderer_);
  const engine::FrameView& view = renderer_->frame_view();
  const glm::vec3 to_light = -view.light_direction;
  reference::EmbreeTracer tracer(scene_->registry);
  const float tan_half = std::tan(0.5f * glm::radians(view.light_angular_diameter_degrees));
  const auto sharp = support::sub_pixel_penumbra_mask(points, h.reference, tracer, to_light, tan_half,
                                                      2.0f * std::tan(0.5f * view.vertical_fov) / 256.0f);
  size_t sharp_pixels = 0, differing = 0, soft = 0;
  std::vector<uint8_t> include(sharp.size(), 0);
  for (size_t i = 0; i < sharp.size(); ++i) {
    if (h.visibility[i] != hard.visibility[i] && !sharp[i]) ++soft;
    if (!sharp[i]) continue;
    include[i] = 1;
    ++sharp_pixels;
    differing += h.visibility[i] != hard.visibility[i] ? 1 : 0;
  }
  const auto cmp = reference::compare_visibility(h.visibility, h.reference, include);
  std::printf("hybrid: %zu pixels under sub-pixel penumbrae, %zu differ from the IZB; %zu softened elsewhere\n",
              sharp_pixels, differing, soft);
  EXPECT_GT(sharp_pixels, 40000u);
  EXPECT_EQ(differing, 0u);
  EXPECT_LE(cmp.mismatch_rate, 0.0002);
}

// The hybrid's cascades filter only the pixels of its fade band and beyond (a limited range): a range
// beyond the view and a sun of size 0 leave the IZB's term bit for bit; a range shorter than the near
// plane gives the cascades' term.
TEST_F(IzbTest, HybridFiltersOnlyThePixelsItBlends) {
  sun_degrees_ = 0.0f;
  const auto plain_izb = render("contact", 0, izb(1), false);
  shadows::Settings none;
  none.technique = shadows::Technique::Hybrid;
  none.izb.resolution = kSize;
  none.hybrid_izb_distance = 1.0e6f;
  const auto hard_only = render("contact", 0, none, false);
  EXPECT_EQ(hard_only.visibility, plain_izb.visibility);
  EXPECT_EQ(hard_only.stats.expensive_path_pixels, 0u);  // the cascades filtered nothing
  none.hybrid_izb_distance = 0.0f;  // unlimited: no cascades at all
  EXPECT_EQ(render("contact", 0, none, false).visibility, plain_izb.visibility);
  // Only a limited range hands pixels to the cascades: without one the hybrid holds neither a pixel
  // list nor a soft term of the frame's size (at 3840x2160, 158 MiB).
  constexpr uint32_t kMemorySize = 256;
  const uint64_t pixels = uint64_t(kMemorySize) * kMemorySize;
  for (const float range : {1.0e6f, 0.0f}) {
    SCOPED_TRACE(range);
    shadows::Settings hybrid = none;
    hybrid.hybrid_izb_distance = range;
    const auto held = render("contact", 0, hybrid, false, 1, kMemorySize).stats.memory_bytes;
    ASSERT_TRUE(held.count("izb hybrid pixel list") && held.count("izb hybrid soft term"));
    EXPECT_EQ(held.at("izb hybrid pixel list") >= 16 * pixels, range > 0.0f);
    EXPECT_EQ(held.at("izb hybrid soft term") >= 4 * pixels, range > 0.0f);
  }

  shadows::Settings cascades_only;
  cascades_only.technique = shadows::Technique::Cascades;
  cascades_only.cascades.masking = shadows::Masking::Off;  // what Auto takes in the hybrid
  const auto soft = render("contact", 0, cascades_only, false);
  shadows::Settings all = none;
  all.hybrid_izb_distance = 1.0e-4f;
  const auto soft_only = render("contact", 0, all, false);
  ASSERT_EQ(soft_only.visibility.size(), soft.visibility.size());
  // The blur takes no neighbours from pixels facing away (never listed), which the cascades-only
  // blur may take at a curved surface's terminator: allow those few.
  size_t same = 0;
  for (size_t i = 0; i < soft.visibility.size(); ++i) same += soft_only.visibility[i] == soft.visibility[i] ? 1 : 0;
  EXPECT_GE(double(same), 0.998 * double(soft.visibility.size()));
  EXPECT_GT(soft_only.stats.expensive_path_pixels, 0u);
}

// With a limited range the hybrid hands the cascades only the pixels past 0.9 of it: the cascades
// that end nearer the camera than any of those are not drawn, and the pixels past the range still get
// the term the cascades alone give them.
TEST_F(IzbTest, HybridDrawsOnlyTheCascadesItsPixelsRead) {
  for (const std::string scene : {"atrium", "canopy"}) {
    SCOPED_TRACE(scene);
    shadows::Settings cascades_only;
    cascades_only.technique = shadows::Technique::Cascades;
    cascades_only.cascades.masking = shadows::Masking::Off;  // what Auto takes in the hybrid
    cascades_only.cascades.blur = false;  // the hybrid's blur takes no neighbours from unlisted pixels
    const auto soft = render(scene, 0, cascades_only, false);
    const std::vector<float> splits = soft.stats.cascade_splits;
    ASSERT_EQ(splits.size(), 5u);
    EXPECT_EQ(soft.stats.cascades_drawn, 4u);
    // A range whose fade band starts past the second split even at the frustum's corners (60 degrees
    // vertically, a square image: their rays make 37.8 degrees with the axis).
    const float range = 1.5f * splits[2] / 0.9f;
    shadows::Settings hybrid = cascades_only;
    hybrid.technique = shadows::Technique::Hybrid;
    hybrid.izb.resolution = kSize;
    hybrid.hybrid_izb_distance = range;
    const auto mixed = render(scene, 0, hybrid, false);
    EXPECT_LE(mixed.stats.cascades_drawn, 2u);
    const auto positions = renderer_->read_world_positions();
    const glm::vec3 eye = scene_->views[0].eye;
    size_t beyond = 0, differing = 0;
    for (size_t i = 0; i < positions.size(); ++i) {
      if (positions[i].w == 0.0f || glm::distance(glm::vec3(positions[i]), eye) <= 1.001f * range) continue;
      ++beyond;
      differing += mixed.visibility[i] != soft.visibility[i] ? 1 : 0;
    }
    EXPECT_GT(beyond, 500u);
    EXPECT_EQ(differing, 0u);
  }
}

}  // namespace

namespace {

// Every overlay the panel offers draws something over the lit image, without validation messages
// (the hybrid with a limited range, so that its cascades run and their overlays have pixels).
TEST_F(IzbTest, DebugOverlaysDrawOverTheImage) {
  auto& r = make_renderer("atrium", 0, 96, 96);
  shadows::Settings s;
  s.technique = shadows::Technique::Hybrid;
  s.hybrid_izb_distance = 20.0f;
  s.izb.resolution = 256;
  s.izb.csm = true;
  module_ = shadows::install(r, s);
  // The second frame: the first one's may differ in a pixel (the module's first-frame choices).
  for (int i = 0; i < 2; ++i) r.render_frame(0.0f);
  const auto plain = r.read_output_rgba8();
  // Not just "changed": each overlay recolours a part of the image (seen: 91 %, 91 %, 2.9 %, 82 %, 2.9 %;
  // the cascades and the expensive path cover only the pixels the hybrid lists), and no two look alike.
  auto changed_share = [](const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
    size_t changed = 0;
    for (size_t i = 0; i + 3 < a.size(); i += 4) changed += std::memcmp(&a[i], &b[i], 3) != 0;
    return double(changed) / double(a.size() / 4);
  };
  std::vector<std::vector<uint8_t>> overlays;
  for (auto view : {shadows::DebugView::VisibilityMask, shadows::DebugView::ListLength,
                    shadows::DebugView::Cascades, shadows::DebugView::CsmCoverage,
                    shadows::DebugView::ExpensivePath}) {
    module_->settings().debug = view;
    r.render_frame(0.0f);
    overlays.push_back(r.read_output_rgba8());
    const double share = changed_share(overlays.back(), plain);
    std::printf("overlay %d: %.3f of the pixels changed\n", int(view), share);
    EXPECT_GT(share, 0.01) << "overlay " << int(view);
    for (size_t k = 0; k + 1 < overlays.size(); ++k)
      EXPECT_NE(overlays[k], overlays.back()) << "overlays " << k << " and " << overlays.size() - 1 << " look alike";
  }
  // Without a debug view the module is handed no overlay, and the renderer clears the one the last
  // view drew (it clears only what nothing wrote): the image is the plain one again, bit for bit.
  module_->settings().debug = shadows::DebugView::None;
  r.render_frame(0.0f);
  EXPECT_EQ(r.read_output_rgba8(), plain) << "the last overlay left behind";
}

// Shadows off with no debug view: the engine records none of the module's passes, and the renderer
// rests the term the IZB wrote at lit (it clears what nothing wrote): every pixel 1 and the frame
// without a `shadows` region.
TEST_F(IzbTest, OffRecordsNothingAndLeavesEveryPixelLit) {
  auto& r = make_renderer("contact", 0, 96, 96);
  module_ = shadows::install(r, izb(1));
  r.render_frame(0.0f);
  const auto shadowed = r.read_shadow_term();
  ASSERT_LT(*std::min_element(shadowed.begin(), shadowed.end()), 1.0f) << "the view has no shadow to clear";
  module_->settings().technique = shadows::Technique::Off;
  for (int i = 0; i < 3; ++i) r.render_frame(0.0f);
  const auto term = r.read_shadow_term();
  EXPECT_EQ(std::count(term.begin(), term.end(), 1.0f), std::ptrdiff_t(term.size())) << "a pixel not lit";
  for (const auto& [name, ms] : r.profiler().last_frame()) EXPECT_NE(name, "shadows") << "the module recorded";
}

// The renderer's sun term filled with `value` between two frames (what the next frame's passes find).
void fill_shadow_term(engine::Renderer& r, float value) {
  r.context().immediate_submit([&](VkCommandBuffer cmd) {
    const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    const VkClearColorValue color{{value, value, value, value}};
    // The last frame's lighting read the term; the next frame's passes read and write it.
    engine::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT,
                                VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    vkCmdClearColorImage(cmd, r.shadow_term().handle(), VK_IMAGE_LAYOUT_GENERAL, &color, 1, &range);
    engine::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                                VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
  });
}

// The frame after the last one rendered over a term poisoned with 0.25: its term, how many pixels
// differ bit for bit from the last frame's, and how many uncovered pixels (per `positions`) it left
// other than lit.
struct PoisonedFrame {
  std::vector<float> term;
  size_t differing = 0, uncovered_not_lit = 0;
};
PoisonedFrame render_over_poison(engine::Renderer& r, const std::vector<glm::vec4>& positions) {
  const auto expected = r.read_shadow_term();
  fill_shadow_term(r, 0.25f);
  r.render_frame(0.0f);
  PoisonedFrame frame{r.read_shadow_term()};
  EXPECT_EQ(frame.term.size(), positions.size());
  for (size_t i = 0; i < frame.term.size() && i < positions.size(); ++i) {
    frame.differing += std::memcmp(&frame.term[i], &expected[i], sizeof(float)) != 0;
    frame.uncovered_not_lit += positions[i].w == 0.0f && frame.term[i] != 1.0f;
  }
  return frame;
}

// The sun's term gets no lit fill before a technique whose passes write every one of its pixels
// (ContextImpl::writes_every_pixel: sm and the cascades everywhere, the IZB's direct term on a GPU):
// with the image holding another value before the frame, every technique leaves the same term, bit
// for bit, and the pixels the G-buffer does not cover lit.
TEST_F(IzbTest, EveryTechniqueWritesTheWholeTermWhateverTheImageHeld) {
  auto& r = make_renderer("atrium", 1, 96, 96);
  module_ = shadows::install(r, izb(1));
  r.render_frame(0.0f);
  const auto positions = r.read_world_positions();
  const auto uncovered = std::count_if(positions.begin(), positions.end(), [](const glm::vec4& p) { return p.w == 0.0f; });
  ASSERT_GT(uncovered, 0) << "the view shows no sky, so no pixel tests the uncovered ones";
  using T = shadows::Technique;
  for (T technique : {T::ShadowMap, T::Cascades, T::Izb, T::Hybrid}) {
    module_->settings().technique = technique;
    r.render_frame(0.0f);
    const PoisonedFrame poisoned = render_over_poison(r, positions);
    EXPECT_EQ(poisoned.differing, 0u) << shadows::mode_name(module_->settings());
    EXPECT_EQ(poisoned.uncovered_not_lit, 0u) << shadows::mode_name(module_->settings());
  }
}

// On a GPU's paths (SHADOWS_GPU_PATHS=1) a spot light's map is resolved over the whole frame, which
// writes every pixel (ContextImpl::writes_every_pixel), so its term gets no lit fill either: with the
// image holding another value before the frame, `sm`, `cascades` and the IZB leave the same term bit
// for bit, the uncovered pixels lit.
TEST_F(IzbTest, ASpotLightsTermIsWrittenWholeOnAGpusPaths) {
  setenv("SHADOWS_GPU_PATHS", "1", 1);
  auto& r = make_renderer("atrium", 1, 96, 96);
  module_ = shadows::install(r, izb(1));
  unsetenv("SHADOWS_GPU_PATHS");  // read when the module was created
  r.render_frame(0.0f);
  const auto positions = r.read_world_positions();
  glm::dvec3 centre(0.0);
  size_t covered = 0;
  for (const glm::vec4& p : positions)
    if (p.w != 0.0f) centre += glm::dvec3(p), ++covered;
  ASSERT_GT(covered, 0u);
  ASSERT_LT(covered, positions.size()) << "the view shows no sky, so no pixel tests the uncovered ones";
  centre /= double(covered);
  // Above the middle of the view, pointing down: it reaches part of the view (not every pixel).
  shadows::Light spot{.type = shadows::LightType::Spot, .range = 30.0f, .outer_cone = 0.5f};
  const glm::vec3 position = glm::vec3(centre) + glm::vec3(0.0f, 6.0f, 0.0f);
  std::memcpy(spot.position, &position, sizeof(spot.position));
  module_->set_light(spot);
  using T = shadows::Technique;
  for (T technique : {T::ShadowMap, T::Cascades, T::Izb}) {
    module_->settings().technique = technique;
    r.render_frame(0.0f);
    r.render_frame(0.0f);  // the statistics of a frame that has completed
    ASSERT_EQ(module_->stats().lights.size(), 1u);
    EXPECT_TRUE(module_->stats().lights[0].reaches_view) << "the light reaches no point: its passes would not run";
    const PoisonedFrame poisoned = render_over_poison(r, positions);
    size_t lit = 0;
    for (size_t i = 0; i < poisoned.term.size() && i < positions.size(); ++i)
      lit += positions[i].w != 0.0f && poisoned.term[i] > 0.0f;
    std::printf("%s, a spot light on a GPU's paths: %zu of %zu covered pixels lit, %zu differ after the poison\n",
                shadows::mode_name(module_->settings()).c_str(), lit, covered, poisoned.differing);
    EXPECT_GT(lit, 0u) << "the light lights no covered pixel";
    EXPECT_LT(lit, covered) << "the light reaches every covered pixel: the cone's edge is not tested";
    EXPECT_EQ(poisoned.differing, 0u) << shadows::mode_name(module_->settings());
    EXPECT_EQ(poisoned.uncovered_not_lit, 0u) << shadows::mode_name(module_->settings());
  }
}

}  // namespace

namespace {

// A window resize reaches the module: its per-pixel buffers follow and the answer stays exact.
TEST_F(IzbTest, ResizeKeepsTheAnswerExact) {
  auto& r = make_renderer("contact", 0, 96, 96);
  shadows::Settings s = izb(32);
  module_ = shadows::install(r, s);
  r.render_frame(0.0f);
  for (VkExtent2D size : {VkExtent2D{120, 80}, VkExtent2D{64, 100}}) {
    r.resize(size);
    r.render_frame(0.0f);
    reference::EmbreeTracer tracer(scene_->registry);
    const auto reference = support::reference_visibility(r, tracer, 32);
    const auto visibility = module_->read_visibility();
    ASSERT_EQ(visibility.size(), size_t(size.width) * size.height);
    EXPECT_LE(reference::compare_visibility(visibility, reference).coverage_mae, 1.0e-3);  // the sun suite's bound
  }
  module_->settings().technique = shadows::Technique::Hybrid;
  r.resize({100, 60});
  r.render_frame(0.0f);
}

// Under PassBackend::Auto the module times both passes on its first frames and keeps the one that
// measured faster, reporting both times.
TEST_F(IzbTest, AutomaticBackendsKeepTheFasterMeasuredPass) {
  auto s = izb(1, true);
  s.izb.trace = shadows::PassBackend::Auto;
  s.izb.csm_backend = shadows::PassBackend::Auto;
  auto& r = make_renderer("atrium", 0, kSize, kSize);
  scene_->registry.each<engine::ShadowCaster>([](engine::Entity, engine::ShadowCaster& c) { c.csm = engine::CsmChoice::On; });
  module_ = shadows::install(r, s);
  EXPECT_EQ(module_->stats().trace_choice.reason, "");
  // Both probe at once, each until its backends' last two frames agree (at most 4 frames each).
  for (int i = 0; i < 12 && (i < 6 || module_->stats().trace_choice.reason == "probing" ||
                             module_->stats().csm_choice.reason == "probing");
       ++i)
    r.render_frame(0.0f);
  for (const auto* choice : {&module_->stats().trace_choice, &module_->stats().csm_choice}) {
    EXPECT_EQ(choice->reason.rfind("auto: ", 0), 0u) << choice->reason;
    EXPECT_GT(choice->raster_ms, 0.0);
    EXPECT_GT(choice->compute_ms, 0.0);
    EXPECT_EQ(choice->backend, choice->compute_ms <= choice->raster_ms ? "compute" : "raster") << choice->reason;
  }
  // A new size is a new configuration: probing starts again.
  r.resize({kSize / 2, kSize / 2});
  r.render_frame(0.0f);
  EXPECT_EQ(module_->stats().trace_choice.reason, "probing");
}

}  // namespace
