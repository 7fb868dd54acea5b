// Windowed presentation on a virtual X server: the scene and the ImGui overlay reach the swapchain,
// a resize is followed by the swapchain and the renderer, and validation stays silent throughout.
#include <cstdlib>
#include <set>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <imgui.h>

#include "engine/assets/scene.hpp"
#include "gpu/context.hpp"
#include "engine/platform/window.hpp"
#include "engine/render/renderer.hpp"

namespace {

using engine::platform::Window;

// Overlay placement: the test looks for it exactly here.
constexpr int kUiWidth = 160;
constexpr int kUiHeight = 60;

struct Frame {
  std::vector<uint8_t> rgba;
  uint32_t width = 0;
  uint32_t height = 0;
  const uint8_t* at(uint32_t x, uint32_t y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

// Frames may be skipped while the swapchain catches up with a resize; keep going until `count` drew.
// With `capture`, each frame is captured, so last_frame reads the last one drawn.
void draw_frames(Window& window, engine::Renderer& renderer, const std::function<void()>& ui, int count,
                 bool capture = true) {
  int drawn = 0;
  for (int attempt = 0; attempt < 100 && drawn < count; ++attempt) {
    window.poll_events();
    if (capture) window.capture_next_frame();
    if (window.draw_frame(renderer, ui, 1.0f / 60.0f)) ++drawn;
  }
  ASSERT_EQ(drawn, count) << "frames kept being skipped";
}

Frame last_frame(Window& window) {
  Frame f;
  f.rgba = window.read_last_frame(f.width, f.height);
  return f;
}

int difference(const uint8_t* a, const uint8_t* b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

}  // namespace

TEST(Window, FailsWithOneLineWithoutDisplay) {
  const char* display = std::getenv("DISPLAY");
  const std::string saved = display ? display : "";
  unsetenv("DISPLAY");
  std::string message;
  try {
    Window window(engine::platform::WindowOptions{"no display", 64, 64});
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
  ASSERT_FALSE(message.empty()) << "a window opened without a display";
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

// Run with the renderer's frames in flight: 1, and 2 under synchronization validation.
class WindowInFlight : public ::testing::TestWithParam<uint32_t> {};

TEST_P(WindowInFlight, PresentsSceneAndOverlayThroughResize) {
  const uint32_t in_flight = GetParam();
  engine::gpu::ContextOptions options;
  options.device = "lavapipe";
  options.validation = true;
  options.sync_validation = in_flight > 1;
  options.instance_extensions = Window::required_instance_extensions();
  options.swapchain = true;
  engine::gpu::Context ctx(options);
  EXPECT_TRUE(ctx.validation_enabled());

  Window window(engine::platform::WindowOptions{"window test", 320, 240});
  window.attach(ctx);
  auto scene = engine::load_scene("contact");
  engine::Renderer renderer(ctx, {320, 240}, in_flight);
  renderer.set_scene(*scene);

  bool show_ui = true;
  const auto ui = [&] {
    if (!show_ui) return;
    ImGui::SetNextWindowPos(ImVec2(0.0f, 0.0f));
    ImGui::SetNextWindowSize(ImVec2(float(kUiWidth), float(kUiHeight)));
    ImGui::Begin("shadow engine", nullptr, ImGuiWindowFlags_NoScrollbar);
    ImGui::Text("shadow engine ui");
    ImGui::Text("frame %llu", static_cast<unsigned long long>(renderer.frame_view().frame_index));
    ImGui::End();
  };

  draw_frames(window, renderer, ui, 3);
  EXPECT_EQ(renderer.extent().width, 320u);
  EXPECT_EQ(renderer.extent().height, 240u);

  window.set_size(400, 300);
  window.poll_events();
  draw_frames(window, renderer, ui, 3);
  EXPECT_EQ(window.framebuffer_extent().width, 400u);
  EXPECT_EQ(window.framebuffer_extent().height, 300u);
  EXPECT_EQ(renderer.extent().width, 400u);
  EXPECT_EQ(renderer.extent().height, 300u);

  // The same view without the overlay, to tell the overlay's pixels from the scene's.
  show_ui = false;
  draw_frames(window, renderer, ui, 1);
  const Frame plain = last_frame(window);
  show_ui = true;
  draw_frames(window, renderer, ui, 1);
  const Frame shown = last_frame(window);

  ASSERT_EQ(shown.width, 400u);
  ASSERT_EQ(shown.height, 300u);
  ASSERT_EQ(shown.rgba.size(), size_t(400) * 300 * 4);
  ASSERT_EQ(plain.rgba.size(), shown.rgba.size());
  engine::write_rgba8_png("window_test.png", shown.width, shown.height, shown.rgba.data());

  // Scene: the area below the overlay holds many colours, and matches the frame without overlay.
  std::set<uint32_t> colours;
  size_t outside_changed = 0, outside = 0;
  for (uint32_t y = kUiHeight + 8; y < shown.height; ++y) {
    for (uint32_t x = 0; x < shown.width; ++x) {
      const uint8_t* p = shown.at(x, y);
      colours.insert(uint32_t(p[0]) << 16 | uint32_t(p[1]) << 8 | p[2]);
      ++outside;
      if (difference(p, plain.at(x, y)) > 6) ++outside_changed;
    }
  }
  EXPECT_GT(colours.size(), 32u) << "the scene did not reach the window";
  EXPECT_LT(outside_changed, outside / 100) << "the overlay leaked outside its window";

  // Overlay: its nearly opaque dark background changes most of its rectangle, and its text adds
  // bright pixels the scene cannot show through that background.
  size_t inside_changed = 0, bright = 0;
  const size_t inside = size_t(kUiWidth) * kUiHeight;
  for (uint32_t y = 0; y < uint32_t(kUiHeight); ++y) {
    for (uint32_t x = 0; x < uint32_t(kUiWidth); ++x) {
      const uint8_t* p = shown.at(x, y);
      if (difference(p, plain.at(x, y)) > 24) ++inside_changed;
      if (y > 22 && p[0] > 180 && p[1] > 180 && p[2] > 180) ++bright;
    }
  }
  EXPECT_GT(inside_changed, inside / 2) << "no overlay in the top-left corner";
  EXPECT_GT(bright, 30u) << "no overlay text";

  // A second resize, shrinking, exercises swapchain replacement once more under validation.
  window.set_size(256, 200);
  draw_frames(window, renderer, ui, 2);
  EXPECT_EQ(renderer.extent().width, 256u);
  EXPECT_EQ(renderer.extent().height, 200u);
  uint32_t w = 0, h = 0;
  EXPECT_EQ(window.read_last_frame(w, h).size(), size_t(256) * 200 * 4);
  EXPECT_EQ(w, 256u);
  EXPECT_EQ(h, 200u);

  // Frames drawn without a capture request are not copied: after the next resize nothing is readable.
  window.set_size(200, 160);
  draw_frames(window, renderer, ui, 2, false);
  EXPECT_TRUE(window.read_last_frame(w, h).empty());
  EXPECT_EQ(w, 0u);

  // Never more than the frames in flight pending; once finished, every drawn frame was timed once.
  EXPECT_LE(renderer.frames_pending(), size_t(in_flight));
  renderer.finish_frames();
  EXPECT_EQ(renderer.frames_pending(), 0u);
  if (renderer.profiler().enabled()) {
    EXPECT_EQ(renderer.profiler().history("frame").size(), 12u);
  }

  for (const auto& m : ctx.validation_messages()) ADD_FAILURE() << m;
  EXPECT_EQ(ctx.validation_message_count(), 0u);
}

INSTANTIATE_TEST_SUITE_P(FramesInFlight, WindowInFlight, ::testing::Values(1u, 2u),
                         [](const ::testing::TestParamInfo<uint32_t>& info) {
                           return std::to_string(info.param) + "_in_flight";
                         });
