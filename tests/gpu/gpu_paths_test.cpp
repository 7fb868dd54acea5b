// The paths a GPU takes, run on lavapipe (SHADOWS_GPU_PATHS=1), against the CPU device's own: every
// light's term the same, bit for bit, for every technique. A GPU's paths differ where a CPU device pays
// for every lane of a SIMD row: the IZB's build stores every pixel's term itself (no fill), its lists
// grow by subgroup, the light frustum culls the casters in its fit's last workgroup, the compute trace
// and CSM take other workgroup shapes, the term starts lit by compute stores instead of a clear, and a
// point light's faces record each IZB step together.
// CI has no GPU: this is where those paths meet the validation layer and the CPU paths' answers.
#include <cstdlib>
#include <string>
#include <vector>

#include "gpu_fixture.hpp"

namespace {

struct PathsCase {
  std::string scene;
  size_t view;
};
void PrintTo(const PathsCase& c, std::ostream* os) { *os << c.scene << " view " << c.view; }

class GpuPathsTest : public GpuTest, public ::testing::WithParamInterface<PathsCase> {
 protected:
  // The sun's term and each local light's after `frames` frames of `settings`, on the CPU device's
  // paths or a GPU's.
  std::vector<std::vector<float>> terms(const shadows::Settings& settings, int frames, bool gpu_paths) {
    if (gpu_paths) setenv("SHADOWS_GPU_PATHS", "1", 1);
    auto& r = make_renderer(GetParam().scene, GetParam().view, kSize, kSize);
    auto module = shadows::install(r, settings);
    unsetenv("SHADOWS_GPU_PATHS");  // read when the module was created
    for (int f = 0; f < frames; ++f) r.render_frame(0.0f);
    // The path taken: a CPU device culls the IZB's casters in a step of its own (with step timings on).
    if (settings.technique == shadows::Technique::Izb || settings.technique == shadows::Technique::Hybrid) {
      bool cpu_cull = false;
      for (const auto& pass : module->context().pass_times()) cpu_cull = cpu_cull || pass.name == "light_frustum_cull";
      EXPECT_EQ(cpu_cull, !gpu_paths) << "the IZB took the other device's paths";
    }
    std::vector<std::vector<float>> out = {r.read_shadow_term()};
    for (uint32_t i = 0; i < r.frame_view().local_lights.size(); ++i) out.push_back(r.read_local_shadow_term(i));
    r.finish_frames();
    module.reset();
    renderer_.reset();
    return out;
  }
  static constexpr uint32_t kSize = 64;
};

TEST_P(GpuPathsTest, EveryTechniqueGivesTheCpuPathsTerms) {
  if (ctx_->properties().deviceType != VK_PHYSICAL_DEVICE_TYPE_CPU)
    GTEST_SKIP() << "a GPU takes these paths already";
  shadows::Settings base;
  base.izb.resolution = 256;
  base.izb.step_timings = true;  // names the CPU paths' own step (terms())
  base.shadow_map.size = 512;
  base.cascades.map_size = 512;
  // `izb` alone records a point light's faces together on a GPU's paths (IzbPass::record_faces), one
  // after another on a CPU device's and with the CSM.
  const TechniqueCase techniques[] = {{"izb", shadows::Technique::Izb, 1, false},
                                      {"izb+csm", shadows::Technique::Izb, 1, true},
                                      {"izb 32 spp", shadows::Technique::Izb, 32, false},
                                      {"sm", shadows::Technique::ShadowMap, 1, false},
                                      {"cascades", shadows::Technique::Cascades, 1, false},
                                      {"hybrid+csm", shadows::Technique::Hybrid, 1, true}};
  for (const TechniqueCase& t : techniques) {
    SCOPED_TRACE(t.name);
    const shadows::Settings settings = t.applied_to(base);
    const auto cpu = terms(settings, t.frames() + 1, false);
    const auto gpu = terms(settings, t.frames() + 1, true);
    ASSERT_EQ(cpu.size(), gpu.size());
    size_t shadowed = 0;
    for (size_t light = 0; light < cpu.size(); ++light) {
      size_t differ = 0;
      for (size_t i = 0; i < cpu[light].size(); ++i) {
        differ += cpu[light][i] != gpu[light][i];
        shadowed += cpu[light][i] >= 0.0f && cpu[light][i] < 1.0f;
      }
      EXPECT_EQ(differ, 0u) << "light " << light << ": " << differ << " pixels differ from the CPU paths'";
    }
    EXPECT_GT(shadowed, 0u) << "nothing shadowed: the comparison would prove little";
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, GpuPathsTest,
                         ::testing::Values(PathsCase{"contact", 1}, PathsCase{"atrium", 0}, PathsCase{"lamps", 0}),
                         [](const auto& info) { return info.param.scene + "_view" + std::to_string(info.param.view); });

}  // namespace
