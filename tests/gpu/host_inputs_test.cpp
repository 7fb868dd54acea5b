// The engine's own frames through the module's host path: the adapter hands the G-buffer over as any
// other engine would (ShadowModule::set_host_inputs: depth, normals, geometric normals with the
// light-facing decision, terminator offset, receiver mask), the module's input pass rebuilds the
// shading points, and every technique's visibility is the same, bit for bit, as with the native
// shading points the rest of the suite reads (whose terms the module writes into the renderer's image
// in place, where the host path's output pass copies them). A representative third of the suite's scenes, views,
// lights and techniques.
#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "gpu_fixture.hpp"

namespace {

struct HostInputsCase {
  std::string scene;
  size_t view;
  uint32_t size;
};
void PrintTo(const HostInputsCase& c, std::ostream* os) { *os << c.scene << " view " << c.view; }

class HostInputsTest : public GpuTest, public ::testing::WithParamInterface<HostInputsCase> {};

TEST_P(HostInputsTest, EveryTechniqueMatchesTheNativePathBitForBit) {
  const HostInputsCase& c = GetParam();
  auto& r = make_renderer(c.scene, c.view, c.size, c.size);
  shadows::Settings base;
  base.izb.resolution = 256;
  // Fixed backends: both paths record the same passes on every frame.
  base.izb.trace = shadows::PassBackend::Compute;
  base.izb.csm_backend = shadows::PassBackend::Compute;
  base.izb.lit_culling = shadows::LitCulling::Off;
  base.shadow_map.size = 512;
  base.cascades.map_size = 512;
  auto module = shadows::install(r, base);
  const TechniqueCase techniques[] = {{"izb", shadows::Technique::Izb, 1, false},
                                  {"izb+csm", shadows::Technique::Izb, 1, true},
                                  {"izb 32 spp", shadows::Technique::Izb, 32, false},
                                  {"sm", shadows::Technique::ShadowMap, 1, false},
                                  {"cascades", shadows::Technique::Cascades, 1, false},
                                  {"hybrid", shadows::Technique::Hybrid, 1, false}};
  for (const TechniqueCase& t : techniques) {
    SCOPED_TRACE(t.name);
    std::vector<float> visibility[2];
    for (int host = 0; host < 2; ++host) {
      module->set_host_inputs(host == 1);
      module->settings() = t.applied_to(base);
      for (int f = 0; f < t.frames(); ++f) r.render_frame(0.0f);
      visibility[host] = module->read_visibility();
      // The path taken: the input pass runs exactly when the G-buffer is handed over as host inputs;
      // the native path writes the renderer's R32F term in place, with no output pass (whose copy the
      // host path still takes: the two agree bit for bit below).
      bool input_pass = false, output_pass = false;
      for (const auto& pass : module->context().pass_times()) {
        input_pass = input_pass || pass.name == "host_inputs";
        output_pass = output_pass || pass.name == "host_output";
      }
      EXPECT_EQ(input_pass, host == 1);
      EXPECT_EQ(output_pass, host == 1);
    }
    ASSERT_EQ(visibility[0].size(), size_t(c.size) * c.size);
    size_t differ = 0, first = visibility[0].size();
    for (size_t i = 0; i < visibility[0].size(); ++i)
      if (visibility[0][i] != visibility[1][i]) {
        ++differ;
        first = std::min(first, i);
      }
    EXPECT_EQ(differ, 0u) << "pixels differ from the native path; the first at " << first;
    size_t shadowed = 0;
    for (float v : visibility[0]) shadowed += v >= 0.0f && v < 1.0f;
    EXPECT_GT(shadowed, 0u) << "nothing shadowed: the comparison would prove little";
  }
  r.finish_frames();
  module.reset();
}

// ENGINE_HOST_INPUTS=1 (the host_inputs_suite entries) starts every module on the host path; unset,
// the engine's native shading points are read in place.
TEST_F(GpuTest, HostInputsEnvironmentPicksThePath) {
  const char* env = std::getenv("ENGINE_HOST_INPUTS");
  const bool host = env && *env && std::string(env) != "0";
  auto& r = make_renderer("contact", 0, 64, 64);
  auto module = shadows::install(r, {});
  r.render_frame(0.0f);
  bool input_pass = false;
  for (const auto& pass : module->context().pass_times()) input_pass = input_pass || pass.name == "host_inputs";
  EXPECT_EQ(input_pass, host) << "ENGINE_HOST_INPUTS=" << (env ? env : "(unset)");
  r.finish_frames();
  module.reset();
}

INSTANTIATE_TEST_SUITE_P(Scenes, HostInputsTest,
                         ::testing::Values(HostInputsCase{"contact", 0, 128}, HostInputsCase{"atrium", 1, 128},
                                           HostInputsCase{"foliage", 0, 128}, HostInputsCase{"canopy", 1, 128},
                                           HostInputsCase{"lamps", 0, 128}),
                         [](const auto& info) { return info.param.scene + "_view" + std::to_string(info.param.view); });

}  // namespace
