#pragma once
// The walkthrough game: a camera that walks a path through the scene's views, and the ImGui panel
// that switches shadow modes and shows GPU pass timings.
#include <memory>

#include "engine/assets/scene.hpp"
#include "engine/render/renderer.hpp"
#include "shadows/shadows.hpp"

namespace walkthrough {

// Moves the camera smoothly from view to view (looping), `seconds_per_view` each; the light follows
// the current view's light direction. Registered as an ECS system.
class CameraPath {
 public:
  CameraPath(engine::Scene& scene, float seconds_per_view) : scene_(scene), seconds_per_view_(seconds_per_view) {}
  void update(float dt);
  void set_paused(bool paused) { paused_ = paused; }
  bool paused() const { return paused_; }
  float time() const { return time_; }

 private:
  engine::Scene& scene_;
  float seconds_per_view_;
  float time_ = 0.0f;
  bool paused_ = false;
};

// Draws the control panel (call between ImGui::NewFrame and ImGui::Render).
void draw_panel(engine::Renderer& renderer, shadows::ShadowModule& shadows, CameraPath& path);

}  // namespace walkthrough
