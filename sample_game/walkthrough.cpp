#include "walkthrough.hpp"

#include <cmath>

#include <imgui.h>

#include "engine/core/transform_system.hpp"

namespace walkthrough {

void CameraPath::update(float dt) {
  if (paused_ || scene_.views.empty()) return;
  time_ += dt;
  const size_t count = scene_.views.size();
  const float t = time_ / seconds_per_view_;
  const size_t from = size_t(std::floor(t)) % count;
  const size_t to = (from + 1) % count;
  float f = t - std::floor(t);
  f = f * f * (3.0f - 2.0f * f);  // ease in and out at each view
  const auto& a = scene_.views[from];
  const auto& b = scene_.views[to];
  engine::place_camera(scene_.registry, scene_.camera, glm::mix(a.eye, b.eye, f), glm::mix(a.target, b.target, f));
  if (scene_.light.valid() && scene_.registry.has<engine::DirectionalLight>(scene_.light)) {
    scene_.registry.get<engine::DirectionalLight>(scene_.light).direction =
        glm::normalize(glm::mix(glm::normalize(a.light_direction), glm::normalize(b.light_direction), f));
  }
}

void draw_panel(engine::Renderer& renderer, shadows::ShadowModule& module, CameraPath& path) {
  auto& shadows = module;
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Shadows");
  auto& s = module.settings();
  const char* techniques[] = {"off", "shadow map", "cascades", "IZB", "hybrid"};
  int technique = int(s.technique);
  if (ImGui::Combo("technique", &technique, techniques, IM_ARRAYSIZE(techniques)))
    s.technique = shadows::Technique(technique);
  bool spp32 = s.izb.samples_per_pixel == 32;
  if (ImGui::Checkbox("32 samples per pixel", &spp32)) s.izb.samples_per_pixel = spp32 ? 32 : 1;
  ImGui::Checkbox("CSM z-prepass", &s.izb.csm);
  const char* tests[] = {"hertel", "bary", "bary-hw", "inner-hw"};
  int test = int(s.izb.csm_test);
  if (ImGui::Combo("coverage test", &test, tests, IM_ARRAYSIZE(tests))) {
    std::string why;
    if (module.supported(shadows::CsmTest(test), &why)) s.izb.csm_test = shadows::CsmTest(test);
  }
  const char* maskings[] = {"off", "edge", "depth extent"};
  int masking = int(s.cascades.masking);
  if (ImGui::Combo("masking", &masking, maskings, IM_ARRAYSIZE(maskings))) s.cascades.masking = shadows::Masking(masking);
  ImGui::Checkbox("selective blur", &s.cascades.blur);
  const char* debug_views[] = {"none", "visibility mask", "IZB list length", "cascades", "CSM coverage", "expensive path"};
  int debug = int(s.debug);
  if (ImGui::Combo("overlay", &debug, debug_views, IM_ARRAYSIZE(debug_views))) s.debug = shadows::DebugView(debug);
  static bool statistics = false;
  if (ImGui::Checkbox("statistics (extra passes)", &statistics)) shadows.set_collect_stats(statistics);
  bool paused = path.paused();
  if (ImGui::Checkbox("pause camera", &paused)) path.set_paused(paused);

  ImGui::Separator();
  ImGui::Text("GPU time (ms), %ux%u on %s", renderer.extent().width, renderer.extent().height,
              renderer.context().device_name().c_str());
  for (const auto& [name, ms] : renderer.profiler().last_frame()) ImGui::Text("  %-22s %8.3f", name.c_str(), ms);
  const auto& st = module.stats();
  if (s.technique == shadows::Technique::Izb || s.technique == shadows::Technique::Hybrid) {
    ImGui::Separator();
    ImGui::Text("points %llu  nodes %llu", (unsigned long long)st.lit_candidates, (unsigned long long)st.nodes_inserted);
    ImGui::Text("CSM culled %.1f%%  overflow %llu", st.culling_rate * 100.0, (unsigned long long)st.node_overflow);
    ImGui::Text("list avg %.2f max %llu", st.list_length_average, (unsigned long long)st.list_length_max);
  }
  if (s.technique == shadows::Technique::Cascades || s.technique == shadows::Technique::Hybrid)
    ImGui::Text("expensive path %.1f%%", st.expensive_path_fraction * 100.0);
  ImGui::End();
}

}  // namespace walkthrough
