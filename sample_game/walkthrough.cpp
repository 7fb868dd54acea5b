#include "walkthrough.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <imgui.h>
#include <nlohmann/json.hpp>

#include "engine/core/animation.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"

namespace walkthrough {

namespace {
constexpr size_t kHistory = 120;
constexpr float kPi = 3.14159265f;
}  // namespace

// ---------------------------------------------------------------------------------------------
CameraPath::CameraPath(engine::Scene& scene, float seconds_per_view, const CollisionWorld* world)
    : scene_(scene), seconds_per_view_(seconds_per_view) {
  const size_t n = scene.views.size();
  cuts_.assign(n, false);
  if (world && n > 1)
    for (size_t i = 0; i < n; ++i) cuts_[i] = world->segment_blocked(scene.views[i].eye, scene.views[(i + 1) % n].eye);
}

void CameraPath::update(float dt) {
  if (paused_ || scene_.views.empty()) return;
  time_ += dt;
  const size_t count = scene_.views.size();
  const float t = time_ / seconds_per_view_;
  const size_t from = size_t(std::floor(t)) % count;
  const size_t to = (from + 1) % count;
  float f = t - std::floor(t);
  f = cuts_[from] ? 0.0f : f * f * (3.0f - 2.0f * f);  // ease in and out at each view; hold before a cut
  const auto& a = scene_.views[from];
  const auto& b = scene_.views[to];
  engine::place_camera(scene_.registry, scene_.camera, glm::mix(a.eye, b.eye, f), glm::mix(a.target, b.target, f));
  if (drive_light && scene_.light.valid() && scene_.registry.has<engine::DirectionalLight>(scene_.light)) {
    scene_.registry.get<engine::DirectionalLight>(scene_.light).direction =
        glm::normalize(glm::mix(glm::normalize(a.light_direction), glm::normalize(b.light_direction), f));
  }
}

// ---------------------------------------------------------------------------------------------
glm::vec3 sun_direction(const glm::vec3& noon_direction, float hours) {
  const glm::vec3 d = glm::normalize(noon_direction);
  const float noon_elevation = std::asin(std::clamp(-d.y, 0.05f, 1.0f));
  const float azimuth = std::atan2(d.x, d.z) + (hours - 12.0f) * (kPi / 12.0f);
  const float day = std::sin(kPi * (hours - 6.0f) / 12.0f);
  const float elevation = noon_elevation * std::max(day, 0.12f);
  return glm::normalize(glm::vec3(std::cos(elevation) * std::sin(azimuth), -std::sin(elevation),
                                  std::cos(elevation) * std::cos(azimuth)));
}

float daylight(float hours) {
  const float day = std::sin(kPi * (hours - 6.0f) / 12.0f);
  const float t = std::clamp((day + 0.1f) / 0.3f, 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
Game::Game(std::unique_ptr<engine::Scene> scene, float seconds_per_view) : seconds_per_view_(seconds_per_view) {
  set_scene(std::move(scene));
}

void Game::set_scene(std::unique_ptr<engine::Scene> scene) {
  scene_ = std::move(scene);
  engine::Scene& s = *scene_;
  // Rest pose for the collision world; moving objects do not collide.
  engine::update_animations(s.registry, 0.0f);
  engine::update_clip_animations(s.registry, 0.0f);
  collision_ = CollisionWorld::from_scene(s, [&](engine::Entity e) {
    const auto* c = s.registry.try_get<engine::Collider>(e);
    // Skinned and morphing meshes move too (the character's mesh hangs below its walking root).
    return s.registry.has<engine::Animated>(e) || s.registry.has<engine::Skeleton>(e) ||
           s.registry.has<engine::MorphWeights>(e) || (c && !c->solid);
  });
  const engine::SceneView start = s.start ? *s.start : s.views.front();
  player_ = std::make_unique<Player>(&collision_, start.eye, start.target);
  tour_ = std::make_unique<CameraPath>(s, seconds_per_view_, &collision_);
  noon_sun_ = s.views.front().light_direction;
  if (const auto* light = s.registry.try_get<engine::DirectionalLight>(s.light)) {
    noon_sun_ = light->direction;
    sun_color_ = light->color;
    sun_intensity_ = light->intensity;
  }
  day_sky_ = s.sky_color;
  day_sky_brightness_ = s.sky_brightness;
  sim_time = 0.0f;
}

// The sun by day, the moon (dim and blue, opposite the sun's path) by night; the sky and the ambient
// darken with the daylight, and the lamps light at dusk.
void Game::apply_time_of_day() {
  engine::Scene& s = *scene_;
  const float light = daylight(time_of_day);
  if (s.registry.has<engine::DirectionalLight>(s.light)) {
    auto& sun = s.registry.get<engine::DirectionalLight>(s.light);
    const float moon_intensity = 0.06f * sun_intensity_;
    sun.direction = light > 0.05f ? sun_direction(noon_sun_, time_of_day) : sun_direction(noon_sun_, time_of_day + 12.0f);
    sun.color = glm::mix(glm::vec3(0.55f, 0.65f, 1.0f), sun_color_, light);
    sun.intensity = glm::mix(moon_intensity, sun_intensity_, light);
  }
  s.sky_color = glm::mix(glm::vec3(0.025f, 0.035f, 0.06f), day_sky_, light);
  s.sky_brightness = glm::mix(0.06f, day_sky_brightness_, light);
  switch_lamps(light < 0.5f);
}

void Game::switch_lamps(bool on) {
  if (!lamps_follow_time) return;
  scene_->registry.each<engine::SpotLight>([&](engine::Entity, engine::SpotLight& l) { l.enabled = on; });
  scene_->registry.each<engine::PointLight>([&](engine::Entity, engine::PointLight& l) { l.enabled = on; });
}

void Game::update(const InputFrame& input) {
  engine::Scene& s = *scene_;
  if (paused) return;
  const float dt = input.dt;
  sim_time += dt;
  engine::update_animations(s.registry, sim_time);
  engine::update_clip_animations(s.registry, sim_time);
  if (playing) {
    player_->update(input);
    engine::place_camera(s.registry, s.camera, player_->eye(), player_->eye() + player_->forward());
  } else {
    tour_->drive_light = !sun_from_time;
    tour_->update(dt);
  }
  if (animate_sun) {
    time_of_day += dt * day_speed;
    if (time_of_day >= 24.0f) time_of_day -= 24.0f;
  }
  if (sun_from_time || animate_sun) {
    apply_time_of_day();
  } else {
    // The scene's own hour: lamps lit in a night scene (a dark sky), off by day.
    switch_lamps(day_sky_brightness_ < 0.5f);
    if (playing && s.registry.has<engine::DirectionalLight>(s.light))
      s.registry.get<engine::DirectionalLight>(s.light).direction = noon_sun_;
  }
}

// ---------------------------------------------------------------------------------------------
namespace {
const char* kCsmChoices[] = {"off", "on", "auto"};

void object_table(engine::Renderer& renderer, shadows::ShadowModule& module) {
  engine::Scene* scene = renderer.scene();
  if (!scene) return;
  std::map<uint64_t, const shadows::CsmDecision*> decisions;
  for (const auto& d : module.stats().csm_decisions)
    decisions[d.instance_id] = &d;
  if (!ImGui::BeginTable("objects", 5, ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY |
                                           ImGuiTableFlags_SizingFixedFit,
                         ImVec2(0, 260)))
    return;
  ImGui::TableSetupColumn("object");
  ImGui::TableSetupColumn("cast");
  ImGui::TableSetupColumn("recv");
  ImGui::TableSetupColumn("CSM");
  ImGui::TableSetupColumn("in CSM, why");
  ImGui::TableHeadersRow();
  scene->registry.each<engine::ShadowCaster, engine::Mesh>([&](engine::Entity e, engine::ShadowCaster& c, engine::Mesh&) {
    ImGui::PushID(int(e.index));
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    const auto* name = scene->registry.try_get<engine::Name>(e);
    ImGui::TextUnformatted(name ? name->value.c_str() : "?");
    ImGui::TableNextColumn();
    ImGui::Checkbox("##cast", &c.casts_shadow);
    ImGui::TableNextColumn();
    ImGui::Checkbox("##recv", &c.receives_shadow);
    ImGui::TableNextColumn();
    int choice = int(c.csm);
    ImGui::SetNextItemWidth(60);
    if (ImGui::Combo("##csm", &choice, kCsmChoices, 3)) c.csm = engine::CsmChoice(choice);
    ImGui::TableNextColumn();
    auto it = decisions.find((uint64_t(e.index) << 32) | e.generation);
    if (it != decisions.end()) {
      ImGui::Text("%s  %s", it->second->in_csm ? "yes" : "no ", it->second->reason.c_str());
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", it->second->reason.c_str());
    } else {
      ImGui::TextDisabled(c.casts_shadow ? "(no decision yet)" : "(not a caster)");
    }
    ImGui::PopID();
  });
  ImGui::EndTable();
}
}  // namespace

void draw_help(PanelState& panel) {
  if (!panel.show_help) return;
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->Size.x * 0.5f, vp->Size.y * 0.5f), ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::Begin("Help (F1)", &panel.show_help, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextUnformatted(
      "Click the scene: capture the mouse to look around (Esc releases it)\n"
      "W A S D       walk                Shift   sprint\n"
      "Space         jump (fly: up)      Ctrl    fly: down\n"
      "F             fly on/off          T       tour / play\n"
      "P             pause               Tab     panel on/off\n"
      "F12           screenshot          F1      this help\n"
      "Gamepad: left stick walks, right stick looks, A jumps, B flies, LB sprints");
  ImGui::End();
}

// The scene's spot and point lights: each switched on or off (then no longer by the time of day) and
// its colour's intensity and range changed; which of them the renderer shadows this frame (the
// nearest Renderer::kMaxLocalLights whose range reaches the view; their GPU time is in the "light i"
// regions of the GPU time list and in the statistics).
void light_table(engine::Renderer& renderer, Game& game) {
  engine::Scene* scene = renderer.scene();
  if (!scene) return;
  ImGui::Checkbox("lamps follow the time of day", &game.lamps_follow_time);
  const auto& shadowed = renderer.frame_view().local_lights;
  auto row = [&](engine::Entity e, const char* kind, bool& enabled, float& intensity, float& range) {
    ImGui::PushID(int(e.index));
    const auto* name = scene->registry.try_get<engine::Name>(e);
    const bool is_shadowed = std::any_of(shadowed.begin(), shadowed.end(), [&](const auto& l) { return l.entity == e; });
    if (ImGui::Checkbox("##on", &enabled)) game.lamps_follow_time = false;
    ImGui::SameLine();
    ImGui::Text("%s %s%s", kind, name ? name->value.c_str() : "?", is_shadowed ? " (shadowed)" : "");
    ImGui::SetNextItemWidth(120);
    ImGui::SliderFloat("cd", &intensity, 0.0f, 200.0f, "%.0f");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(120);
    ImGui::SliderFloat("range", &range, 0.5f, 40.0f, "%.1f");
    ImGui::PopID();
  };
  scene->registry.each<engine::SpotLight>(
      [&](engine::Entity e, engine::SpotLight& l) { row(e, "spot", l.enabled, l.intensity, l.range); });
  scene->registry.each<engine::PointLight>(
      [&](engine::Entity e, engine::PointLight& l) { row(e, "point", l.enabled, l.intensity, l.range); });
}

void draw_panel(engine::Renderer& renderer, shadows::ShadowModule& module, Game& game, PanelState& panel) {
  // Per-pass GPU time history (kept while the panel is hidden too).
  for (const auto& [name, ms] : renderer.profiler().last_frame()) {
    auto& h = panel.pass_history[name];
    h.push_back(float(ms));
    while (h.size() > kHistory) h.pop_front();
  }
  if (!panel.show_panel) return;
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Shadows");
  if (!panel.status_line.empty()) ImGui::TextUnformatted(panel.status_line.c_str());

  if (ImGui::CollapsingHeader("Scene and game", ImGuiTreeNodeFlags_DefaultOpen)) {
    std::vector<const char*> labels;
    for (const auto& s : panel.scenes) labels.push_back(s.label.c_str());
    int pick = panel.scene_index;
    if (!labels.empty() && ImGui::Combo("scene", &pick, labels.data(), int(labels.size()))) panel.requested_scene = pick;
    ImGui::SameLine();
    if (ImGui::SmallButton("reload")) panel.requested_scene = panel.scene_index;
    if (!panel.scene_error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.4f, 1), "%s", panel.scene_error.c_str());
    ImGui::Checkbox("play (off: tour)", &game.playing);
    ImGui::SameLine();
    ImGui::Checkbox("pause", &game.paused);
    if (game.playing) {
      bool fly = game.player().flying();
      if (ImGui::Checkbox("fly", &fly)) game.player().set_flying(fly);
      const glm::vec3 p = game.player().feet();
      ImGui::SameLine();
      ImGui::Text("at %.1f %.1f %.1f", p.x, p.y, p.z);
    }
    if (ImGui::SliderFloat("time of day", &game.time_of_day, 0.0f, 24.0f, "%.1f h")) game.sun_from_time = true;
    // The sun's size (shadows::Light::angular_diameter_degrees): penumbrae widen with it in sm, cascades
    // and hybrid (and rt with rays over the disc); 0 gives hard shadows everywhere.
    engine::Scene* shown = renderer.scene();
    if (shown && shown->light.valid() && shown->registry.has<engine::DirectionalLight>(shown->light))
      ImGui::SliderFloat("sun size", &shown->registry.get<engine::DirectionalLight>(shown->light).angular_diameter_degrees,
                         0.0f, 10.0f, "%.2f deg");
    if (ImGui::Checkbox("animate sun", &game.animate_sun) && game.animate_sun) game.sun_from_time = true;
    ImGui::SameLine();
    ImGui::SetNextItemWidth(100);
    ImGui::SliderFloat("h/s", &game.day_speed, 0.05f, 2.0f, "%.2f");
    if (auto* dr = panel.dynamic_resolution) {
      ImGui::Checkbox("dynamic resolution", &dr->enabled);
      float fps = 1000.0f / dr->target_ms();
      ImGui::SameLine();
      ImGui::SetNextItemWidth(90);
      if (ImGui::SliderFloat("fps", &fps, 5.0f, 120.0f, "%.0f")) dr->set_target_fps(fps);
      ImGui::Text("render %ux%u (scale %.2f), frame median %.1f ms", renderer.extent().width, renderer.extent().height,
                  dr->scale(), dr->median_ms());
      if (!panel.detail_line.empty()) ImGui::TextUnformatted(panel.detail_line.c_str());
    }
  }

  auto& s = module.settings();
  if (ImGui::CollapsingHeader("Technique", ImGuiTreeNodeFlags_DefaultOpen)) {
    // A technique the device cannot run is listed greyed out, with the device's reason below.
    const char* techniques[] = {"off", "shadow map", "cascades", "IZB", "hybrid", "ray traced"};
    std::string rt_why;
    const bool rt_ok = module.supported(shadows::Technique::RayTraced, &rt_why);
    if (ImGui::BeginCombo("technique", techniques[int(s.technique)])) {
      for (int t = 0; t < IM_ARRAYSIZE(techniques); ++t) {
        const bool usable = shadows::Technique(t) != shadows::Technique::RayTraced || rt_ok;
        if (ImGui::Selectable(techniques[t], int(s.technique) == t, usable ? 0 : ImGuiSelectableFlags_Disabled))
          s.technique = shadows::Technique(t);
      }
      ImGui::EndCombo();
    }
    if (!rt_ok) ImGui::TextDisabled("ray traced: %s", rt_why.c_str());
    if (s.technique == shadows::Technique::RayTraced) {
      int rays = int(s.rt_light_samples);
      if (ImGui::SliderInt("rays over the sun (0: its centre)", &rays, 0, 64)) s.rt_light_samples = uint32_t(rays);
    }
    bool spp32 = s.izb.samples_per_pixel == 32;
    if (ImGui::Checkbox("32 samples per pixel", &spp32)) s.izb.samples_per_pixel = spp32 ? 32 : 1;
    ImGui::Checkbox("CSM z-prepass", &s.izb.csm);
    int lit = int(s.izb.lit_culling);
    if (ImGui::Combo("known-lit culling", &lit, "off\0on\0auto\0")) s.izb.lit_culling = shadows::LitCulling(lit);
    const char* tests[] = {"hertel", "bary", "bary-hw", "inner-hw"};
    int test = int(s.izb.csm_test);
    if (ImGui::Combo("coverage test", &test, tests, IM_ARRAYSIZE(tests))) {
      std::string why;
      if (module.supported(shadows::CsmTest(test), &why)) s.izb.csm_test = shadows::CsmTest(test);
    }
    // Raster or compute passes: auto times both on the first frames and keeps the faster.
    const char* backends[] = {"auto", "raster", "compute"};
    int trace = int(s.izb.trace);
    if (ImGui::Combo("trace pass", &trace, backends, IM_ARRAYSIZE(backends))) s.izb.trace = shadows::PassBackend(trace);
    int csm_backend = int(s.izb.csm_backend);
    if (ImGui::Combo("CSM pass", &csm_backend, backends, IM_ARRAYSIZE(backends)))
      s.izb.csm_backend = shadows::PassBackend(csm_backend);
    const char* maskings[] = {"off", "edge", "depth extent", "auto", "planes"};  // shadows::Masking's order
    int masking = int(s.cascades.masking);
    if (ImGui::Combo("masking", &masking, maskings, IM_ARRAYSIZE(maskings))) s.cascades.masking = shadows::Masking(masking);
    ImGui::Checkbox("selective blur", &s.cascades.blur);
    ImGui::Checkbox("sm masking (the same term)", &s.shadow_map.masking);
    ImGui::Checkbox("sm local light tiles (the same term)", &s.shadow_map.local_light_tiles);
    const char* debug_views[] = {"none", "visibility mask", "IZB list length", "cascades", "CSM coverage", "expensive path"};
    int debug = int(s.debug);
    if (ImGui::Combo("overlay", &debug, debug_views, IM_ARRAYSIZE(debug_views))) s.debug = shadows::DebugView(debug);
    if (ImGui::Checkbox("statistics (extra passes)", &panel.statistics)) module.set_collect_stats(panel.statistics);
  }

  if (ImGui::CollapsingHeader("Lights")) light_table(renderer, game);

  if (ImGui::CollapsingHeader("GPU time", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Text("GPU ms, %ux%u on %s", renderer.extent().width, renderer.extent().height,
                renderer.context().device_name().c_str());
    // Times and statistics describe the frame that completed last, frames in flight - 1 behind.
    ImGui::Text("frames in flight: %u", renderer.frames_in_flight());
    for (const auto& [name, ms] : renderer.profiler().last_frame()) {
      auto it = panel.pass_history.find(name);
      if (it == panel.pass_history.end() || it->second.empty()) continue;
      std::vector<float> values(it->second.begin(), it->second.end());
      const float peak = *std::max_element(values.begin(), values.end());
      char label[96];
      std::snprintf(label, sizeof(label), "%-16.16s %7.2f", name.c_str(), ms);
      ImGui::PlotLines(label, values.data(), int(values.size()), 0, nullptr, 0.0f, std::max(peak, 0.01f) * 1.1f,
                       ImVec2(150, 22));
    }
  }

  const auto& st = module.stats();
  if (ImGui::CollapsingHeader("Statistics")) {
    if (!panel.statistics) ImGui::TextDisabled("turn on 'statistics' above for live numbers");
    if (s.technique == shadows::Technique::Izb || s.technique == shadows::Technique::Hybrid) {
      ImGui::Text("points %llu  nodes %llu", (unsigned long long)st.lit_candidates, (unsigned long long)st.nodes_inserted);
      const double pool = st.node_pool_size ? double(st.nodes_inserted) / double(st.node_pool_size) : 0.0;
      ImGui::ProgressBar(float(std::min(pool, 1.0)), ImVec2(-1, 0), nullptr);
      ImGui::Text("node pool %llu used of %llu (%.0f%%), overflow %llu", (unsigned long long)st.nodes_inserted,
                  (unsigned long long)st.node_pool_size, pool * 100.0, (unsigned long long)st.node_overflow);
      ImGui::Text("CSM culled %.1f%% (%s)", st.culling_rate * 100.0, st.csm_status.c_str());
      ImGui::Text("list avg %.2f max %llu", st.list_length_average, (unsigned long long)st.list_length_max);
      ImGui::TextWrapped("trace: %s (%s)", st.trace_choice.backend.c_str(), st.trace_choice.reason.c_str());
      if (!st.csm_choice.backend.empty())
        ImGui::TextWrapped("CSM: %s (%s)", st.csm_choice.backend.c_str(), st.csm_choice.reason.c_str());
    }
    if (s.technique == shadows::Technique::Cascades || s.technique == shadows::Technique::Hybrid) {
      ImGui::Text("expensive path %.1f%%", st.expensive_path_fraction * 100.0);
      if (!st.cascade_splits.empty())
        ImGui::Text("cascades drawn %u of %zu", st.cascades_drawn, st.cascade_splits.size() - 1);
    }
    if (s.technique == shadows::Technique::RayTraced)
      ImGui::Text("rays %llu (%.2f per point), occluded %llu; %llu instances", (unsigned long long)st.rays_traced,
                  st.lit_candidates ? double(st.rays_traced) / double(st.lit_candidates) : 0.0,
                  (unsigned long long)st.rays_occluded, (unsigned long long)st.rt_instances);
    if (s.technique == shadows::Technique::Izb || s.technique == shadows::Technique::Hybrid)
      ImGui::Text("triangle tests %.1f per point", st.triangle_tests_per_pixel);
    // Per light of the frame (the sun's and the lamps' records), with the GPU time of its passes.
    for (size_t i = 0; i < st.lights.size(); ++i) {
      const auto& l = st.lights[i];
      ImGui::Text("light %zu %-11s %6.2f ms  points %llu  nodes %llu  rays %llu", i, l.kind.c_str(), l.gpu_ms,
                  (unsigned long long)l.lit_candidates, (unsigned long long)l.nodes_inserted,
                  (unsigned long long)l.rays_traced);
      // A point light's cube-face cones that can hold a point of the view (the others are skipped).
      if (l.faces_recorded > 0) {
        ImGui::SameLine();
        ImGui::Text(" cones %u of 6", l.faces_recorded);
      }
      // A lamp that reaches no point of the view runs no pass (its term is written as unlit).
      if (!l.reaches_view) {
        ImGui::SameLine();
        ImGui::TextUnformatted(" out of view: no pass");
      }
    }
    // GPU memory the technique holds, largest resources first.
    ImGui::Text("GPU memory %.1f MiB", double(st.memory_total_bytes) / (1024.0 * 1024.0));
    std::vector<std::pair<uint64_t, std::string>> resources;
    for (const auto& [name, bytes] : st.memory_bytes) resources.emplace_back(bytes, name);
    std::sort(resources.rbegin(), resources.rend());
    for (size_t i = 0; i < resources.size() && i < 6; ++i)
      ImGui::Text("  %-30.30s %8.1f MiB", resources[i].second.c_str(), double(resources[i].first) / (1024.0 * 1024.0));
  }


  if (ImGui::CollapsingHeader("Settings file")) {
    static char path[256] = {};
    if (!path[0]) std::snprintf(path, sizeof(path), "%s", panel.settings_path.c_str());
    ImGui::InputText("file", path, sizeof(path));
    panel.settings_path = path;
    if (ImGui::Button("save")) {
      panel.settings_message = save_settings(panel.settings_path, module, game, panel.dynamic_resolution);
      if (panel.settings_message.empty()) panel.settings_message = "saved " + panel.settings_path;
    }
    ImGui::SameLine();
    if (ImGui::Button("load")) {
      panel.settings_message = load_settings(panel.settings_path, module, game, panel.dynamic_resolution);
      if (panel.settings_message.empty()) panel.settings_message = "loaded " + panel.settings_path;
    }
    if (!panel.settings_message.empty()) ImGui::TextWrapped("%s", panel.settings_message.c_str());
  }
  ImGui::End();

  // The per-object shadow table in its own window on the right.
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->Size.x - 8, 8), ImGuiCond_FirstUseEver, ImVec2(1.0f, 0.0f));
  ImGui::SetNextWindowSize(ImVec2(std::min(560.0f, vp->Size.x * 0.45f), 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(panel.objects_start_collapsed, ImGuiCond_FirstUseEver);
  ImGui::Begin("Objects: shadow flags and the CSM decision");
  object_table(renderer, module);
  if (renderer.scene()) {
    const auto characters = animated_meshes(*renderer.scene());
    if (!characters.empty()) {
      ImGui::Separator();
      ImGui::TextUnformatted("Skinned and morphing meshes (deformed on the GPU each frame)");
      for (const auto& c : characters)
        ImGui::Text("%s: %u joints, %u morph targets, %llu triangles", c.name.c_str(), c.joints, c.morph_targets,
                    (unsigned long long)c.triangles);
    }
  }
  ImGui::End();
}

std::vector<AnimatedMeshInfo> animated_meshes(engine::Scene& scene) {
  std::vector<AnimatedMeshInfo> out;
  scene.registry.each<engine::Mesh>([&](engine::Entity e, engine::Mesh& mesh) {
    if (!mesh.data || !mesh.data->deform) return;
    AnimatedMeshInfo info;
    const auto* name = scene.registry.try_get<engine::Name>(e);
    info.name = name ? name->value : mesh.data->name;
    const auto* skeleton = scene.registry.try_get<engine::Skeleton>(e);
    info.joints = skeleton ? uint32_t(skeleton->joints.size()) : 0u;
    info.morph_targets = uint32_t(mesh.data->deform->morph_targets.size());
    info.triangles = mesh.data->triangle_count();
    out.push_back(std::move(info));
  });
  return out;
}

// ---------------------------------------------------------------------------------------------
std::string save_settings(const std::string& path, shadows::ShadowModule& module, const Game& game,
                          const DynamicResolution* dynres) {
  const auto& s = module.settings();
  nlohmann::json j;
  j["mode"] = shadows::mode_name(s);
  j["samples_per_pixel"] = s.izb.samples_per_pixel;
  j["csm"] = s.izb.csm;
  j["csm_test"] = shadows::csm_test_name(s.izb.csm_test);
  j["trace"] = shadows::backend_name(s.izb.trace);
  j["csm_backend"] = shadows::backend_name(s.izb.csm_backend);
  j["masking"] = shadows::masking_name(s.cascades.masking);
  j["blur"] = s.cascades.blur;
  j["sm_masking"] = s.shadow_map.masking;
  j["sm_local_light_tiles"] = s.shadow_map.local_light_tiles;
  j["debug"] = int(s.debug);
  j["izb_resolution"] = s.izb.resolution;
  j["hybrid_izb_distance"] = s.hybrid_izb_distance;
  j["rt_light_samples"] = s.rt_light_samples;
  j["time_of_day"] = game.time_of_day;
  j["animate_sun"] = game.animate_sun;
  j["day_speed"] = game.day_speed;
  if (dynres) {
    j["dynamic_resolution"] = dynres->enabled;
    j["target_fps"] = 1000.0f / dynres->target_ms();
  }
  std::ofstream out(path);
  if (!out) return path + ": cannot write settings";
  out << j.dump(2) << "\n";
  return out ? "" : path + ": write failed";
}

std::string load_settings(const std::string& path, shadows::ShadowModule& module, Game& game, DynamicResolution* dynres) {
  std::ifstream in(path);
  if (!in) return path + ": cannot open settings";
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const std::exception&) {
    return path + ": not valid JSON";
  }
  if (!j.is_object()) return path + ": expected a JSON object";
  shadows::Settings s = module.settings();
  float tod = game.time_of_day, speed = game.day_speed;
  bool animate = game.animate_sun;
  try {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string& k = it.key();
      const auto& v = it.value();
      auto bad = [&](const std::string& why) { return path + ": " + k + ": " + why; };
      if (k == "mode") {
        auto m = shadows::parse_mode(v.get<std::string>(), s);
        if (!m) return bad("not a shadow mode");
        std::string why;
        if (!module.supported(m->technique, &why)) return bad(why);
        s = *m;
      } else if (k == "samples_per_pixel") {
        const int n = v.get<int>();
        if (n != 1 && n != 32) return bad("must be 1 or 32");
        s.izb.samples_per_pixel = uint32_t(n);
      } else if (k == "csm") s.izb.csm = v.get<bool>();
      else if (k == "csm_test") {
        auto t = shadows::parse_csm_test(v.get<std::string>());
        if (!t || !module.supported(*t)) return bad("unknown or unsupported coverage test");
        s.izb.csm_test = *t;
      } else if (k == "trace" || k == "csm_backend") {
        auto b = shadows::parse_backend(v.get<std::string>());
        if (!b) return bad("expected auto, raster or compute");
        (k == "trace" ? s.izb.trace : s.izb.csm_backend) = *b;
      } else if (k == "masking") {
        auto m = shadows::parse_masking(v.get<std::string>());
        if (!m) return bad("unknown masking");
        s.cascades.masking = *m;
      } else if (k == "blur") s.cascades.blur = v.get<bool>();
      else if (k == "sm_masking") s.shadow_map.masking = v.get<bool>();
      else if (k == "sm_local_light_tiles") s.shadow_map.local_light_tiles = v.get<bool>();
      else if (k == "debug") {
        const int d = v.get<int>();
        if (d < 0 || d > 5) return bad("must be 0..5");
        s.debug = shadows::DebugView(d);
      } else if (k == "izb_resolution") {
        const int r = v.get<int>();
        if (r < 64 || r > 8192) return bad("must be 64..8192");
        s.izb.resolution = uint32_t(r);
      } else if (k == "hybrid_izb_distance") s.hybrid_izb_distance = v.get<float>();
      else if (k == "rt_light_samples") {
        const int n = v.get<int>();
        if (n < 0 || n > 64) return bad("must be 0..64");
        s.rt_light_samples = uint32_t(n);
      } else if (k == "hybrid_soft_distance") return bad("no longer a setting: penumbrae follow the sun's size");
      else if (k == "time_of_day") tod = std::clamp(v.get<float>(), 0.0f, 24.0f);
      else if (k == "animate_sun") animate = v.get<bool>();
      else if (k == "day_speed") speed = std::clamp(v.get<float>(), 0.0f, 10.0f);
      else if (k == "dynamic_resolution" || k == "target_fps") continue;
      else return bad("unknown setting");
    }
  } catch (const nlohmann::json::exception&) {
    return path + ": a value has the wrong type";
  }
  module.settings() = s;
  game.time_of_day = tod;
  game.day_speed = speed;
  game.animate_sun = animate;
  game.sun_from_time = true;
  if (dynres) {
    if (j.contains("dynamic_resolution") && j["dynamic_resolution"].is_boolean()) dynres->enabled = j["dynamic_resolution"];
    if (j.contains("target_fps") && j["target_fps"].is_number()) dynres->set_target_fps(j["target_fps"].get<float>());
  }
  return "";
}

}  // namespace walkthrough
