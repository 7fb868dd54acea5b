#pragma once
// The walkthrough game: a first-person player or a camera tour through the scene's views, moving
// casters and sun, dynamic resolution, and the ImGui panel.
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "collision.hpp"
#include "dynamic_resolution.hpp"
#include "engine/assets/scene.hpp"
#include "engine/render/renderer.hpp"
#include "input.hpp"
#include "player.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace walkthrough {

// Moves the camera smoothly from view to view (looping), `seconds_per_view` each; the light follows
// the current view's light direction. A leg whose straight line would cross the scene's geometry is
// a cut instead (the camera holds the first view, then jumps), so the tour never passes through walls.
class CameraPath {
 public:
  CameraPath(engine::Scene& scene, float seconds_per_view, const CollisionWorld* world = nullptr);
  void update(float dt);
  void set_paused(bool paused) { paused_ = paused; }
  bool paused() const { return paused_; }
  float time() const { return time_; }
  // Whether leg i (view i to view i+1) is a cut.
  const std::vector<bool>& cuts() const { return cuts_; }
  bool drive_light = true;

 private:
  engine::Scene& scene_;
  float seconds_per_view_;
  float time_ = 0.0f;
  bool paused_ = false;
  std::vector<bool> cuts_;
};

// Sun direction for a time of day (hours): the scene's sun at noon, rising in the east of its
// azimuth at 6 and setting at 18 (kept a little above the horizon outside those hours).
glm::vec3 sun_direction(const glm::vec3& noon_direction, float hours);
// How much of the sun's light the hour has: 1 from about 7 to 17 h, 0 from about 19 to 5 h (night),
// smooth at dawn and dusk.
float daylight(float hours);

// A skinned or morphing mesh of the scene, as the panel lists it.
struct AnimatedMeshInfo {
  std::string name;
  uint32_t joints = 0;
  uint32_t morph_targets = 0;
  uint64_t triangles = 0;
};
std::vector<AnimatedMeshInfo> animated_meshes(engine::Scene& scene);

struct SceneEntry {
  std::string label;
  std::string source;  // procedural name, .gltf or .json path
};

class Game {
 public:
  explicit Game(std::unique_ptr<engine::Scene> scene, float seconds_per_view);
  // Replaces the scene (the caller hands it to the renderer).
  void set_scene(std::unique_ptr<engine::Scene> scene);
  engine::Scene& scene() { return *scene_; }
  // One simulation step: player or tour, animations, sun. Registered as an ECS system.
  void update(const InputFrame& input);

  bool playing = true;      // false: the camera tour
  bool paused = false;
  bool animate_sun = false;
  float time_of_day = 12.0f;  // hours, 0..24
  float day_speed = 0.25f;    // hours per second while the sun animates
  bool sun_from_time = false; // the time-of-day slider moved, or the sun animates
  // While the time of day drives the sun, the scene's spot and point lights switch on at dusk and off
  // at dawn (a light switched by hand in the panel stops following).
  bool lamps_follow_time = true;
  float sim_time = 0.0f;      // drives the animations
  Player& player() { return *player_; }
  CameraPath& tour() { return *tour_; }
  const CollisionWorld& collision() const { return collision_; }
  glm::vec3 noon_sun() const { return noon_sun_; }

 private:
  std::unique_ptr<engine::Scene> scene_;
  float seconds_per_view_;
  CollisionWorld collision_;
  std::unique_ptr<Player> player_;
  std::unique_ptr<CameraPath> tour_;
  glm::vec3 noon_sun_{0.0f, -1.0f, 0.0f};
  // The scene's own sun and sky, which the time of day scales toward the moon and the night sky.
  glm::vec3 sun_color_{1.0f};
  float sun_intensity_ = 3.0f;
  glm::vec3 day_sky_{0.26f, 0.31f, 0.40f};
  float day_sky_brightness_ = 1.0f;
  void apply_time_of_day();
  void switch_lamps(bool on);  // unless lamps_follow_time is off
};

// Panel state that outlives one frame.
struct PanelState {
  bool show_panel = true;
  bool show_help = false;
  bool statistics = false;
  // The per-object table's window starts collapsed (its title bar alone): on a CPU device drawing its
  // rows took 1.9 of the interface's 4.6 ms a frame (lavapipe, 1280x720), time dynamic resolution
  // gives to the picture instead.
  bool objects_start_collapsed = false;
  std::vector<SceneEntry> scenes;
  int scene_index = 0;
  std::optional<int> requested_scene;  // set by the picker; main loads it
  std::string scene_error;             // the last load failure, shown in the panel
  std::string settings_path = "walkthrough_settings.json";
  std::string settings_message;
  std::map<std::string, std::deque<float>> pass_history;  // per-pass GPU ms, last kHistory frames
  DynamicResolution* dynamic_resolution = nullptr;
  std::string detail_line;  // how finely generated content was built, and why
  std::string status_line;
};

void draw_panel(engine::Renderer& renderer, shadows::ShadowModule& shadows, Game& game, PanelState& panel);
void draw_help(PanelState& panel);

// Shadow + game settings as JSON. load returns an error line ("" on success); it changes nothing on
// error.
std::string save_settings(const std::string& path, shadows::ShadowModule& module, const Game& game,
                          const DynamicResolution* dynres);
std::string load_settings(const std::string& path, shadows::ShadowModule& module, Game& game, DynamicResolution* dynres);

}  // namespace walkthrough
