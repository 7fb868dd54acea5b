#pragma once
// A GLFW window with a Vulkan swapchain that shows the renderer's output and an ImGui overlay.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "gpu/context.hpp"
#include "engine/render/renderer.hpp"

struct GLFWwindow;

namespace engine::platform {

struct WindowOptions {
  std::string title = "shadow engine";
  uint32_t width = 1280;
  uint32_t height = 720;
};

class Window {
 public:
  // Initialises GLFW and creates the window; throws std::runtime_error with one line on failure.
  explicit Window(const WindowOptions& options);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // Instance extensions the window system needs; pass them in ContextOptions::instance_extensions.
  static std::vector<const char*> required_instance_extensions();

  // Creates the surface, swapchain and ImGui state for `ctx` (which must have swapchain enabled).
  void attach(gpu::Context& ctx);
  bool should_close() const;
  void poll_events();
  // Framebuffer size in pixels (0 x 0 while minimised).
  VkExtent2D framebuffer_extent() const;
  void set_size(uint32_t width, uint32_t height);
  // The renderer draws at the framebuffer size times this factor (0.1..1, each axis); presentation
  // scales its output up to the window. Dynamic resolution changes it between frames.
  void set_render_scale(float scale);
  float render_scale() const;
  // The render size draw_frame will give the renderer for a framebuffer size.
  VkExtent2D render_extent(VkExtent2D framebuffer) const;
  // The GLFW window, for games that read input directly (keys, mouse, gamepads).
  GLFWwindow* native_handle() const;

  // One frame: update + record the renderer, blit its output to the swapchain, draw ImGui built by
  // `build_ui`, present. Handles resize and minimise (skips drawing while minimised). Returns false
  // if the frame was skipped.
  bool draw_frame(Renderer& renderer, const std::function<void()>& build_ui, float dt);
  // The next frame draw_frame draws (not one it skips) is also copied for read_last_frame. Only
  // requested frames are copied: the readback of a whole window costs a CPU device every frame.
  void capture_next_frame();
  // Reads back the last captured swapchain image (scene + overlay) as RGBA8; empty (0 x 0) when no
  // frame was captured since the swapchain last changed size.
  std::vector<uint8_t> read_last_frame(uint32_t& width, uint32_t& height);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace engine::platform
