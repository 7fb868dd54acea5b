// The walkthrough: loads a scene, installs the shadow module and walks the camera through the scene's
// views. Windowed with an ImGui panel when a display exists; otherwise headless, writing PNGs.
#include <cstdio>
#include <filesystem>
#include <string>

#include <imgui.h>

#include "engine/assets/scene.hpp"
#include "engine/core/command_line.hpp"
#include "engine/platform/headless.hpp"
#include "engine/platform/window.hpp"
#include "engine/render/renderer.hpp"
#include "shadows/shadows.hpp"
#include "walkthrough.hpp"

namespace {

struct Options {
  std::string scene = "contact";
  uint32_t width = 1280, height = 720;
  int frames = -1;  // -1: until the window closes (windowed) or 4 (headless)
  bool headless = false;
  std::string screenshot;
  std::string out_dir = "walkthrough_out";
  std::string device;
  std::string mode = "hybrid";
  float seconds_per_view = 6.0f;
};

const char* kUsage =
    "usage: walkthrough [--scene contact|atrium|foliage|FILE.gltf] [--size WxH] [--frames N] [--headless]\n"
    "                   [--screenshot FILE.png] [--out DIR] [--device gpu|lavapipe|INDEX]\n"
    "                   [--mode off|sm|cascades|izb|izb+csm|hybrid|hybrid+csm] [--seconds-per-view S]\n";

Options parse(int argc, char** argv) {
  Options o;
  engine::CommandLine args(argc, argv);
  while (args.next()) {
    const std::string& a = args.flag();
    if (a == "--scene") o.scene = args.value();
    else if (a == "--size") args.size_value(o.width, o.height);
    else if (a == "--frames") o.frames = int(args.uint_value());
    else if (a == "--headless") o.headless = true;
    else if (a == "--screenshot") o.screenshot = args.value();
    else if (a == "--out") o.out_dir = args.value();
    else if (a == "--device") o.device = args.value();
    else if (a == "--mode") o.mode = args.value();
    else if (a == "--seconds-per-view") {
      const std::string v = args.value();
      try {
        o.seconds_per_view = std::stof(v);
      } catch (const std::exception&) {
        throw std::runtime_error("--seconds-per-view '" + v + "': expected a number of seconds");
      }
      if (!(o.seconds_per_view > 0.0f)) throw std::runtime_error("--seconds-per-view must be positive");
    }
    else if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else throw std::runtime_error("unknown option " + a + " (see --help)");
  }
  return o;
}

int run_headless(const Options& o, engine::Scene& scene) {
  engine::gpu::Context ctx({.device = o.device});
  engine::Renderer renderer(ctx, {o.width, o.height});
  renderer.set_scene(scene);
  auto settings = shadows::parse_mode(o.mode, {});
  auto module = shadows::install(renderer, *settings);
  walkthrough::CameraPath path(scene, o.seconds_per_view);
  renderer.systems().add("camera path", [&](engine::Registry&, float dt) { path.update(dt); });

  const int frames = o.frames > 0 ? o.frames : 4;
  const float dt = o.seconds_per_view * float(scene.views.size()) / float(frames);  // one loop over all views
  std::filesystem::create_directories(o.out_dir);
  std::printf("headless: %s on %s (%s), %ux%u, mode %s\n", scene.name.c_str(), ctx.device_name().c_str(),
              ctx.driver_description().c_str(), o.width, o.height, o.mode.c_str());
  for (int f = 0; f < frames; ++f) {
    renderer.render_frame(f == 0 ? 0.0f : dt);
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%03d.png", f);
    const auto path_png = std::filesystem::path(o.out_dir) / name;
    renderer.write_png(path_png);
    std::printf("  wrote %s  (gpu frame %.2f ms)\n", path_png.c_str(), renderer.profiler().average_ms("frame", 1));
  }
  if (!o.screenshot.empty()) {
    renderer.write_png(o.screenshot);
    std::printf("  wrote %s\n", o.screenshot.c_str());
  }
  return 0;
}

int run_windowed(const Options& o, engine::Scene& scene) {
  // The window's swapchain and ImGui state belong to the device: everything that uses the device is
  // released before the window, and the window before the context.
  std::unique_ptr<engine::platform::Window> window;
  try {
    window = std::make_unique<engine::platform::Window>(engine::platform::WindowOptions{
        .title = "shadow engine walkthrough: " + scene.name, .width = o.width, .height = o.height});
  } catch (const std::exception& e) {
    // A display variable without a usable display server: still do the job, headless.
    std::printf("%s: running headless\n", e.what());
    return run_headless(o, scene);
  }
  auto ctx = std::make_unique<engine::gpu::Context>(
      engine::gpu::ContextOptions{.device = o.device,
                                  .instance_extensions = engine::platform::Window::required_instance_extensions(),
                                  .swapchain = true});
  window->attach(*ctx);
  const VkExtent2D extent = window->framebuffer_extent();
  auto renderer = std::make_unique<engine::Renderer>(
      *ctx, VkExtent2D{std::max(extent.width, 1u), std::max(extent.height, 1u)});
  renderer->set_scene(scene);
  auto module = shadows::install(*renderer, *shadows::parse_mode(o.mode, {}));
  module->set_collect_stats(false);  // the panel's checkbox turns the statistics passes on
  walkthrough::CameraPath path(scene, o.seconds_per_view);
  renderer->systems().add("camera path", [&](engine::Registry&, float dt) { path.update(dt); });
  int frame = 0;
  while (!window->should_close() && (o.frames < 0 || frame < o.frames)) {
    window->poll_events();
    if (window->draw_frame(*renderer, [&] { walkthrough::draw_panel(*renderer, *module, path); }, 1.0f / 60.0f))
      ++frame;
  }
  if (!o.screenshot.empty()) {
    uint32_t w = 0, h = 0;
    auto pixels = window->read_last_frame(w, h);
    engine::write_rgba8_png(o.screenshot, w, h, pixels.data());
    std::printf("wrote %s\n", o.screenshot.c_str());
  }
  vkDeviceWaitIdle(ctx->device());
  module.reset();
  renderer.reset();
  window.reset();
  ctx.reset();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options o = parse(argc, argv);
    if (!shadows::parse_mode(o.mode, {})) throw std::runtime_error("--mode '" + o.mode + "' is not a shadow mode");
    auto scene = engine::load_scene(o.scene);
    if (o.headless || !engine::platform::display_available()) {
      if (!o.headless) std::printf("no display found: running headless\n");
      return run_headless(o, *scene);
    }
    return run_windowed(o, *scene);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "walkthrough: %s\n", e.what());
    return 1;
  }
}
