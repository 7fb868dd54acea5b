#pragma once
// First-person player: walks on the scene's triangles (a capsule of three spheres pushed out of the
// collision world), gravity, jump, sprint, and a fly toggle (no gravity, still collides).
#include <glm/glm.hpp>

#include "collision.hpp"
#include "input.hpp"

namespace walkthrough {

struct PlayerTuning {
  float radius = 0.3f;
  float eye_height = 1.6f;
  float walk_speed = 4.0f;
  float sprint_speed = 8.0f;
  float fly_speed = 6.0f;
  float jump_speed = 5.0f;
  float gravity = 15.0f;
  float mouse_sensitivity = 0.0025f;  // radians per pixel
};

class Player {
 public:
  // Starts at `eye` looking at `target`; dropped onto the floor below when there is one within 20 m,
  // else flying.
  Player(const CollisionWorld* world, const glm::vec3& eye, const glm::vec3& target, PlayerTuning tuning = {});
  void update(const InputFrame& input);
  void set_world(const CollisionWorld* world) { world_ = world; }

  glm::vec3 eye() const { return feet_ + glm::vec3(0.0f, tuning_.eye_height, 0.0f); }
  glm::vec3 forward() const;
  glm::vec3 feet() const { return feet_; }
  float yaw() const { return yaw_; }
  float pitch() const { return pitch_; }
  bool flying() const { return flying_; }
  bool grounded() const { return grounded_; }
  void set_flying(bool f) { flying_ = f; }

 private:
  void step(float h);
  const CollisionWorld* world_;
  PlayerTuning tuning_;
  glm::vec3 feet_{0.0f};
  glm::vec3 velocity_{0.0f};
  float yaw_ = 0.0f;    // 0 looks along -z, positive turns right (towards +x)
  float pitch_ = 0.0f;  // positive looks up
  bool flying_ = false;
  bool grounded_ = false;
  uint32_t previous_keys_ = 0;
};

}  // namespace walkthrough
