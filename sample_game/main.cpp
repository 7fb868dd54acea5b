// The walkthrough: loads a scene (default: the authored courtyard level), installs the shadow module,
// and lets a player walk it (or tours its views). Windowed with an ImGui panel when a display exists;
// otherwise headless, writing PNGs. Input can be recorded to and replayed from a script.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "engine/assets/scene.hpp"
#include "engine/core/command_line.hpp"
#include "engine/platform/headless.hpp"
#include "engine/platform/window.hpp"
#include "engine/render/renderer.hpp"
#include "shadows_engine/shadows_engine.hpp"
#include "walkthrough.hpp"

namespace {

// Each GPU pass's median over the second half of the frames (the first half includes dynamic
// resolution's settling), in the order the passes first ran.
void print_pass_times(const engine::gpu::GpuProfiler& profiler) {
  std::printf("GPU ms per pass, median of the last half of the frames:\n");
  for (const auto& name : profiler.region_names()) {
    auto h = profiler.history(name);
    if (h.empty()) continue;
    h.erase(h.begin(), h.begin() + std::ptrdiff_t(h.size() / 2));
    std::sort(h.begin(), h.end());
    const double median = h[h.size() / 2];
    if (median == 0.0) continue;  // ran in under half those frames (e.g. the other trace backend's probe)
    std::printf("  %-18s %8.2f\n", name.c_str(), median);
  }
}

using walkthrough::InputFrame;

const std::string kContentDir = ENGINE_CONTENT_DIR;
const std::string kDefaultScene = kContentDir + "/levels/courtyard.json";
const std::string kSponza = kContentDir + "/../../shared/content/sponza/sponza.gltf";

struct Options {
  std::string scene = kDefaultScene;
  uint32_t width = 1280, height = 720;
  int frames = -1;  // -1: until the window closes / the script ends (4 for a headless tour)
  bool headless = false;
  bool tour = false;
  std::string screenshot;
  std::string out_dir = "walkthrough_out";
  std::string device;
  std::string mode = "hybrid";
  float seconds_per_view = 6.0f;
  std::string input;
  std::string record;
  std::string settings;
  std::string save_settings;
  bool fixed_size = false;
  float target_fps = 0.0f;  // 0: 30 on a GPU, 10 on a CPU device
  float time_of_day = -1.0f;
  bool animate_sun = false;
  std::string overlay;
  bool stats = false;
  bool pass_times = false;
  std::string switch_scene;  // windowed: picked as if from the panel after the second frame
  uint32_t frames_in_flight = 2;  // windowed; the headless paths record and wait one frame at a time
  std::string detail = "auto";  // generated content: full, low, or auto (low on a CPU device with dynamic resolution)
};

const char* kUsage =
    "usage: walkthrough [--scene NAME|FILE.json|FILE.gltf] [--size WxH] [--frames N] [--headless] [--tour]\n"
    "                   [--input FILE] [--record FILE] [--screenshot FILE.png] [--out DIR]\n"
    "                   [--device gpu|lavapipe|INDEX] [--mode off|sm|cascades|izb|izb+csm|hybrid|hybrid+csm|rt]\n"
    "                   [--seconds-per-view S] [--settings FILE.json] [--save-settings FILE.json] [--fixed-size] [--target-fps F]\n"
    "                   [--time-of-day H] [--animate-sun] [--overlay NAME] [--stats] [--pass-times]\n"
    "                   [--switch-scene FILE] [--detail full|low|auto] [--frames-in-flight 1|2|3]\n";

float float_value(engine::CommandLine& args, float lo, float hi) {
  const std::string flag = args.flag(), v = args.value();
  float out = 0.0f;
  try {
    size_t used = 0;
    out = std::stof(v, &used);
    if (used != v.size()) throw std::invalid_argument(v);
  } catch (const std::exception&) {
    throw std::runtime_error(flag + " '" + v + "': expected a number");
  }
  if (!(out >= lo && out <= hi)) throw std::runtime_error(flag + " '" + v + "': out of range");
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  engine::CommandLine args(argc, argv);
  while (args.next()) {
    const std::string& a = args.flag();
    if (a == "--scene") o.scene = args.value();
    else if (a == "--size") args.size_value(o.width, o.height);
    else if (a == "--frames") o.frames = int(args.uint_value());
    else if (a == "--headless") o.headless = true;
    else if (a == "--tour") o.tour = true;
    else if (a == "--screenshot") o.screenshot = args.value();
    else if (a == "--out") o.out_dir = args.value();
    else if (a == "--device") o.device = args.value();
    else if (a == "--mode") o.mode = args.value();
    else if (a == "--seconds-per-view") o.seconds_per_view = float_value(args, 0.01f, 1e4f);
    else if (a == "--input") o.input = args.value();
    else if (a == "--record") o.record = args.value();
    else if (a == "--settings") o.settings = args.value();
    else if (a == "--save-settings") o.save_settings = args.value();
    else if (a == "--fixed-size") o.fixed_size = true;
    else if (a == "--target-fps") o.target_fps = float_value(args, 1.0f, 1000.0f);
    else if (a == "--time-of-day") o.time_of_day = float_value(args, 0.0f, 24.0f);
    else if (a == "--animate-sun") o.animate_sun = true;
    else if (a == "--overlay") {
      o.overlay = args.value();
      if (!shadows::parse_debug_view(o.overlay))
        throw std::runtime_error("--overlay '" + o.overlay + "': expected none, visibility, list-length, cascades, csm or expensive");
    } else if (a == "--stats") o.stats = true;
    else if (a == "--pass-times") o.pass_times = true;
    else if (a == "--switch-scene") o.switch_scene = args.value();
    else if (a == "--frames-in-flight") {
      const uint32_t n = args.uint_value();
      if (n < 1 || n > engine::Renderer::kMaxFramesInFlight)
        throw std::runtime_error("--frames-in-flight " + std::to_string(n) + ": expected 1 to " +
                                 std::to_string(engine::Renderer::kMaxFramesInFlight));
      o.frames_in_flight = n;
    }
    else if (a == "--detail") {
      o.detail = args.value();
      if (o.detail != "full" && o.detail != "low" && o.detail != "auto")
        throw std::runtime_error("--detail '" + o.detail + "': expected full, low or auto");
    }
    else if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else throw std::runtime_error("unknown option " + a + " (see --help)");
  }
  return o;
}

std::vector<walkthrough::SceneEntry> scene_list(const std::string& current) {
  std::vector<walkthrough::SceneEntry> list;
  std::error_code ec;
  std::vector<std::filesystem::path> levels;
  for (const auto& f : std::filesystem::directory_iterator(kContentDir + "/levels", ec))
    if (f.path().extension() == ".json") levels.push_back(f.path());
  std::sort(levels.begin(), levels.end());
  for (const auto& p : levels) list.push_back({"level: " + p.stem().string(), p.string()});
  for (const auto& n : engine::procedural_scene_names()) list.push_back({"procedural: " + n, n});
  // Sponza with an authored tour and player start when the model is present; also as a plain glTF.
  if (std::filesystem::exists(kSponza, ec)) {
    list.push_back({"Sponza (authored tour)", kContentDir + "/sponza/sponza.json"});
    list.push_back({"Sponza (glTF only)", kSponza});
  }
  bool found = false;
  for (const auto& e : list) found |= std::filesystem::path(e.source) == std::filesystem::path(current) || e.source == current;
  if (!found) list.insert(list.begin(), {std::filesystem::path(current).filename().string(), current});
  return list;
}

void print_player(walkthrough::Game& game) {
  const glm::vec3 p = game.player().feet();
  std::printf("player: feet %.3f %.3f %.3f yaw %.1f pitch %.1f %s%s\n", p.x, p.y, p.z,
              glm::degrees(game.player().yaw()), glm::degrees(game.player().pitch()),
              game.player().flying() ? "flying" : "walking", game.player().grounded() ? " grounded" : "");
}

void apply_options(const Options& o, walkthrough::Game& game) {
  game.playing = !o.tour;
  if (o.time_of_day >= 0.0f) {
    game.time_of_day = o.time_of_day;
    game.sun_from_time = true;
  }
  if (o.animate_sun) game.animate_sun = game.sun_from_time = true;
}

// Keyboard, mouse and gamepad through GLFW, turned into one InputFrame.
class LiveInput {
 public:
  explicit LiveInput(GLFWwindow* w) : window_(w) {}
  InputFrame sample(float dt) {
    InputFrame f;
    f.dt = dt;
    const ImGuiIO& io = ImGui::GetIO();
    auto key = [&](int k) { return !io.WantCaptureKeyboard && glfwGetKey(window_, k) == GLFW_PRESS; };
    if (key(GLFW_KEY_W)) f.keys |= walkthrough::kKeyForward;
    if (key(GLFW_KEY_A)) f.keys |= walkthrough::kKeyLeft;
    if (key(GLFW_KEY_S)) f.keys |= walkthrough::kKeyBack;
    if (key(GLFW_KEY_D)) f.keys |= walkthrough::kKeyRight;
    if (key(GLFW_KEY_LEFT_SHIFT) || key(GLFW_KEY_RIGHT_SHIFT)) f.keys |= walkthrough::kKeySprint;
    if (key(GLFW_KEY_SPACE)) f.keys |= walkthrough::kKeyJump;
    if (key(GLFW_KEY_LEFT_CONTROL) || key(GLFW_KEY_C)) f.keys |= walkthrough::kKeyDown;
    if (key(GLFW_KEY_F)) f.keys |= walkthrough::kKeyFly;
    // Mouse look while captured: a click on the scene captures, Esc releases.
    if (!captured_ && !io.WantCaptureMouse && glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
      captured_ = true;
      glfwSetInputMode(window_, GLFW_CURSOR, GLFW_CURSOR_DISABLED);
      glfwGetCursorPos(window_, &last_x_, &last_y_);
    }
    if (captured_ && glfwGetKey(window_, GLFW_KEY_ESCAPE) == GLFW_PRESS) {
      captured_ = false;
      glfwSetInputMode(window_, GLFW_CURSOR, GLFW_CURSOR_NORMAL);
    }
    if (captured_) {
      double x = 0, y = 0;
      glfwGetCursorPos(window_, &x, &y);
      f.mouse_dx = float(x - last_x_);
      f.mouse_dy = float(y - last_y_);
      last_x_ = x;
      last_y_ = y;
    }
    GLFWgamepadstate pad;
    if (glfwJoystickIsGamepad(GLFW_JOYSTICK_1) && glfwGetGamepadState(GLFW_JOYSTICK_1, &pad)) {
      const float lx = pad.axes[GLFW_GAMEPAD_AXIS_LEFT_X], ly = pad.axes[GLFW_GAMEPAD_AXIS_LEFT_Y];
      if (ly < -0.4f) f.keys |= walkthrough::kKeyForward;
      if (ly > 0.4f) f.keys |= walkthrough::kKeyBack;
      if (lx < -0.4f) f.keys |= walkthrough::kKeyLeft;
      if (lx > 0.4f) f.keys |= walkthrough::kKeyRight;
      auto stick = [](float v) { return std::abs(v) < 0.15f ? 0.0f : v; };
      f.mouse_dx += stick(pad.axes[GLFW_GAMEPAD_AXIS_RIGHT_X]) * 900.0f * dt;
      f.mouse_dy += stick(pad.axes[GLFW_GAMEPAD_AXIS_RIGHT_Y]) * 600.0f * dt;
      if (pad.buttons[GLFW_GAMEPAD_BUTTON_A]) f.keys |= walkthrough::kKeyJump;
      if (pad.buttons[GLFW_GAMEPAD_BUTTON_B]) f.keys |= walkthrough::kKeyFly;
      if (pad.buttons[GLFW_GAMEPAD_BUTTON_LEFT_BUMPER]) f.keys |= walkthrough::kKeySprint;
      if (pad.buttons[GLFW_GAMEPAD_BUTTON_X]) f.keys |= walkthrough::kKeyDown;
    }
    return f;
  }
  // Keys pressed this frame (edge), for the game's own toggles.
  bool pressed(int k) {
    const bool down = glfwGetKey(window_, k) == GLFW_PRESS && !ImGui::GetIO().WantCaptureKeyboard;
    bool& was = previous_[k];
    const bool edge = down && !was;
    was = down;
    return edge;
  }

 private:
  GLFWwindow* window_;
  bool captured_ = false;
  double last_x_ = 0, last_y_ = 0;
  std::map<int, bool> previous_;
};

int run_headless(const Options& o, std::unique_ptr<engine::Scene> scene_in) {
  engine::gpu::Context ctx({.device = o.device});
  // No frame rate to hold here: auto keeps the full detail.
  if (o.detail == "low") scene_in = engine::load_scene(o.scene, engine::Detail::Low);
  walkthrough::Game game(std::move(scene_in), o.seconds_per_view);
  apply_options(o, game);
  engine::Renderer renderer(ctx, {o.width, o.height});
  renderer.set_scene(game.scene());
  auto settings = shadows::parse_mode(o.mode, {});
  if (!o.overlay.empty()) settings->debug = *shadows::parse_debug_view(o.overlay);
  auto module = shadows::install(renderer, *settings);
  if (std::string why; !module->supported(settings->technique, &why)) throw std::runtime_error("--mode " + o.mode + ": " + why);
  module->set_collect_stats(o.stats);
  if (!o.settings.empty()) {
    const std::string err = walkthrough::load_settings(o.settings, *module, game, nullptr);
    if (!err.empty()) throw std::runtime_error(err);
  }
  std::vector<InputFrame> script;
  if (!o.input.empty()) script = walkthrough::load_input_script(o.input);
  // Headless without a script is the camera tour; with one, the player replays it.
  game.playing = !script.empty() && !o.tour;
  InputFrame current;
  renderer.systems().add("game", [&](engine::Registry&, float) { game.update(current); });

  const bool tour = !game.playing;
  const int frames = o.frames > 0 ? o.frames : (tour ? 4 : int(script.size()));
  const float tour_dt = o.seconds_per_view * float(game.scene().views.size()) / float(frames);  // one loop
  std::filesystem::create_directories(o.out_dir);
  std::printf("headless: %s on %s (%s), %ux%u, mode %s, %s\n", game.scene().name.c_str(), ctx.device_name().c_str(),
              ctx.driver_description().c_str(), o.width, o.height, shadows::mode_name(module->settings()).c_str(),
              tour ? "tour" : ("replaying " + o.input).c_str());
  std::vector<InputFrame> recorded;
  for (int f = 0; f < frames; ++f) {
    if (tour) {
      current = InputFrame{f == 0 ? 0.0f : tour_dt, 0, 0.0f, 0.0f};
    } else {
      current = script[std::min(size_t(f), script.size() - 1)];
    }
    recorded.push_back(current);
    renderer.render_frame(current.dt);
    // A tour writes every frame; a replay only its last.
    if (tour || f + 1 == frames) {
      char name[64];
      std::snprintf(name, sizeof(name), "frame_%03d.png", f);
      const auto path_png = std::filesystem::path(o.out_dir) / name;
      renderer.write_png(path_png);
      std::printf("  wrote %s  (gpu frame %.2f ms)\n", path_png.c_str(), renderer.profiler().average_ms("frame", 1));
    }
  }
  if (!tour) print_player(game);
  if (!o.record.empty()) walkthrough::save_input_script(o.record, recorded);
  if (!o.save_settings.empty()) {
    const std::string err = walkthrough::save_settings(o.save_settings, *module, game, nullptr);
    if (!err.empty()) throw std::runtime_error(err);
    std::printf("  saved settings to %s\n", o.save_settings.c_str());
  }
  if (!o.screenshot.empty()) {
    renderer.write_png(o.screenshot);
    std::printf("  wrote %s\n", o.screenshot.c_str());
  }
  return 0;
}

int run_windowed(const Options& o, std::unique_ptr<engine::Scene> scene_in) {
  // The window's swapchain and ImGui state belong to the device: everything that uses the device is
  // released before the window, and the window before the context.
  std::unique_ptr<engine::platform::Window> window;
  try {
    window = std::make_unique<engine::platform::Window>(engine::platform::WindowOptions{
        .title = "shadow engine walkthrough: " + scene_in->name, .width = o.width, .height = o.height});
  } catch (const std::exception& e) {
    // A display variable without a usable display server: still do the job, headless.
    std::printf("%s: running headless\n", e.what());
    return run_headless(o, std::move(scene_in));
  }
  auto ctx = std::make_unique<engine::gpu::Context>(
      engine::gpu::ContextOptions{.device = o.device,
                                  .instance_extensions = engine::platform::Window::required_instance_extensions(),
                                  .swapchain = true});
  window->attach(*ctx);
  const bool cpu = ctx->properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  // Where the frame rate is held on a CPU device, scaling the pixels down is not enough: the leaf cards
  // of generated plants cost the rasterizer per triangle in every pass, so they are built coarser.
  const engine::Detail detail =
      o.detail == "low" || (o.detail == "auto" && cpu && !o.fixed_size) ? engine::Detail::Low : engine::Detail::Full;
  if (detail == engine::Detail::Low) scene_in = engine::load_scene(o.scene, detail);
  walkthrough::Game game(std::move(scene_in), o.seconds_per_view);
  apply_options(o, game);
  const VkExtent2D extent = window->framebuffer_extent();
  auto renderer = std::make_unique<engine::Renderer>(
      *ctx, VkExtent2D{std::max(extent.width, 1u), std::max(extent.height, 1u)}, o.frames_in_flight);
  std::printf("windowed: %s on %s, frames in flight: %u\n", game.scene().name.c_str(), ctx->device_name().c_str(),
              renderer->frames_in_flight());
  renderer->set_scene(game.scene());
  auto mode = *shadows::parse_mode(o.mode, {});
  if (!o.overlay.empty()) mode.debug = *shadows::parse_debug_view(o.overlay);
  auto module = shadows::install(*renderer, mode);
  if (std::string why; !module->supported(mode.technique, &why)) throw std::runtime_error("--mode " + o.mode + ": " + why);
  module->set_collect_stats(o.stats);  // else the panel's checkbox turns the statistics passes on
  // Where the frame rate is held on a CPU device, the IZB's trace (paid per caster triangle and point)
  // covers the hybrid's first 20 m and the cascades the rest: the courtyard's distant plants doubled the
  // trace there (README, "Frame rate"). A settings file may set another range.
  if (cpu && !o.fixed_size) module->settings().hybrid_izb_distance = 20.0f;

  // A CPU device starts at half size: at full size its first frames take most of a second each.
  walkthrough::DynamicResolution dynres(o.target_fps > 0.0f ? o.target_fps : (cpu ? 10.0f : 30.0f),
                                        cpu ? 0.5f : 1.0f);
  dynres.enabled = !o.fixed_size;
  walkthrough::PanelState panel;
  panel.statistics = o.stats;
  panel.scenes = scene_list(o.scene);
  for (size_t i = 0; i < panel.scenes.size(); ++i)
    if (panel.scenes[i].source == o.scene) panel.scene_index = int(i);
  panel.dynamic_resolution = &dynres;
  panel.objects_start_collapsed = cpu;
  panel.detail_line = std::string("generated detail: ") + (detail == engine::Detail::Low ? "low" : "full") +
                      (o.detail == "auto" ? " (auto)" : "");
  if (!o.settings.empty()) {
    panel.settings_path = o.settings;
    const std::string err = walkthrough::load_settings(o.settings, *module, game, &dynres);
    if (!err.empty()) throw std::runtime_error(err);
  }

  // The IZB grid and the cascade maps follow the render scale, so a smaller frame also costs less
  // shadow work (about a grid texel per pixel, as at full size); the sizes set at start are the full ones.
  const uint32_t full_izb = module->settings().izb.resolution;
  const uint32_t full_cascade = module->settings().cascades.map_size;
  auto follow_render_scale = [&](float scale) {
    auto scaled = [&](uint32_t full, uint32_t least) {
      return std::max(least, uint32_t(float(full) * scale / 64.0f + 0.5f) * 64u);
    };
    module->settings().izb.resolution = scaled(full_izb, 128);
    module->settings().cascades.map_size = scaled(full_cascade, 256);
  };
  if (dynres.enabled && dynres.scale() != 1.0f) {
    window->set_render_scale(dynres.scale());
    follow_render_scale(dynres.scale());
  }

  std::vector<InputFrame> script;
  if (!o.input.empty()) {
    script = walkthrough::load_input_script(o.input);
    game.playing = !o.tour;
  }
  std::vector<InputFrame> recorded;
  InputFrame current;
  renderer->systems().add("game", [&](engine::Registry&, float) { game.update(current); });
  LiveInput live(window->native_handle());
  const int frames = o.frames >= 0 ? o.frames : (script.empty() ? -1 : int(script.size()));
  int frame = 0, shots = 0;
  bool switched = false, shot_pending = false;
  auto last = std::chrono::steady_clock::now();
  std::vector<float> frame_ms;
  while (!window->should_close() && (frames < 0 || frame < frames)) {
    window->poll_events();
    const auto now = std::chrono::steady_clock::now();
    const float wall = std::chrono::duration<float>(now - last).count();
    last = now;
    if (frame > 0) {
      frame_ms.push_back(wall * 1000.0f);
      if (dynres.add_frame(wall * 1000.0f)) {
        window->set_render_scale(dynres.scale());
        follow_render_scale(dynres.scale());
      }
    }
    if (!script.empty()) {
      current = script[std::min(size_t(frame), script.size() - 1)];
    } else {
      current = live.sample(std::clamp(wall, 1e-4f, 0.1f));
      if (live.pressed(GLFW_KEY_F1)) panel.show_help = !panel.show_help;
      if (live.pressed(GLFW_KEY_TAB)) panel.show_panel = !panel.show_panel;
      if (live.pressed(GLFW_KEY_P)) game.paused = !game.paused;
      if (live.pressed(GLFW_KEY_T)) game.playing = !game.playing;
      if (live.pressed(GLFW_KEY_F12)) {
        shot_pending = true;  // written once the next frame, which is copied, has been drawn
        window->capture_next_frame();
      }
    }
    if (!o.switch_scene.empty() && frame == 2 && !switched) {
      switched = true;
      panel.scenes.push_back({std::filesystem::path(o.switch_scene).filename().string(), o.switch_scene});
      panel.requested_scene = int(panel.scenes.size()) - 1;
    }
    if (panel.requested_scene) {
      const int pick = *panel.requested_scene;
      panel.requested_scene.reset();
      try {
        auto next = engine::load_scene(panel.scenes[size_t(pick)].source, detail);
        renderer->finish_frames();  // frames in flight still draw the old scene
        game.set_scene(std::move(next));  // the old scene lives until here; the renderer switches next
        renderer->set_scene(game.scene());
        apply_options(o, game);
        panel.scene_index = pick;
        panel.scene_error.clear();
      } catch (const std::exception& e) {
        panel.scene_error = e.what();  // the previous scene stays
        std::fprintf(stderr, "walkthrough: %s (keeping %s)\n", e.what(), game.scene().name.c_str());
      }
    }
    char status[160];
    std::snprintf(status, sizeof(status), "%s  %s  F1 help", game.scene().name.c_str(),
                  game.paused ? "PAUSED" : (game.playing ? (game.player().flying() ? "flying" : "walking") : "tour"));
    if (panel.status_line.rfind("wrote", 0) != 0) panel.status_line = status;
    // --screenshot writes the last frame; without a frame count any frame may be the last.
    if (!o.screenshot.empty() && (frames < 0 || frame + 1 == frames)) window->capture_next_frame();
    if (window->draw_frame(*renderer,
                           [&] {
                             walkthrough::draw_panel(*renderer, *module, game, panel);
                             walkthrough::draw_help(panel);
                           },
                           current.dt)) {
      ++frame;
      if (shot_pending) {
        shot_pending = false;
        uint32_t w = 0, h = 0;
        auto pixels = window->read_last_frame(w, h);
        char name[64];
        std::snprintf(name, sizeof(name), "screenshot_%03d.png", shots++);
        if (w) engine::write_rgba8_png(name, w, h, pixels.data());
        panel.status_line = w ? std::string("wrote ") + name : "screenshot: no frame was captured";
      }
      if (!o.record.empty()) recorded.push_back(current);  // only frames that were simulated
    }
  }
  // The last frames are still in flight: their GPU times and statistics come in here.
  renderer->finish_frames();
  if (game.playing) print_player(game);
  if (!frame_ms.empty()) {
    std::vector<float> sorted = frame_ms;
    std::sort(sorted.begin(), sorted.end());
    const VkExtent2D e = renderer->extent();
    std::printf("frames: %d, median frame %.1f ms, render size %ux%u (scale %.2f)\n", frame, sorted[sorted.size() / 2],
                e.width, e.height, window->render_scale());
    if (o.pass_times) print_pass_times(renderer->profiler());
  }
  if (!o.save_settings.empty()) {
    const std::string err = walkthrough::save_settings(o.save_settings, *module, game, &dynres);
    if (!err.empty()) std::fprintf(stderr, "walkthrough: %s\n", err.c_str());
  }
  if (!o.record.empty()) {
    walkthrough::save_input_script(o.record, recorded);
    std::printf("recorded %zu frames to %s\n", recorded.size(), o.record.c_str());
  }
  int status = 0;
  if (!o.screenshot.empty()) {
    uint32_t w = 0, h = 0;
    auto pixels = window->read_last_frame(w, h);
    if (w) {
      engine::write_rgba8_png(o.screenshot, w, h, pixels.data());
      std::printf("wrote %s\n", o.screenshot.c_str());
    } else {
      std::fprintf(stderr, "walkthrough: --screenshot: no frame was drawn\n");
      status = 1;
    }
  }
  vkDeviceWaitIdle(ctx->device());
  module.reset();
  renderer.reset();
  window.reset();
  ctx.reset();
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options o = parse(argc, argv);
    if (!shadows::parse_mode(o.mode, {})) throw std::runtime_error("--mode '" + o.mode + "' is not a shadow mode");
    if (!o.input.empty()) walkthrough::load_input_script(o.input);  // bad scripts fail before any window opens
    auto scene = engine::load_scene(o.scene);
    if (o.headless || !engine::platform::display_available()) {
      if (!o.headless) std::printf("no display found: running headless\n");
      return run_headless(o, std::move(scene));
    }
    return run_windowed(o, std::move(scene));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "walkthrough: %s\n", e.what());
    return 1;
  }
}
