#pragma once
// Simple procedural animation of an entity's Transform, run as an ECS system: a pendulum swing about
// an axis through the entity's origin, a steady spin, or a walk around a closed path of waypoints.
#include <vector>

#include "engine/core/components.hpp"

namespace engine {

struct Animated {
  enum class Kind { Swing, Spin, Walk };
  Kind kind = Kind::Spin;
  glm::vec3 axis{0.0f, 1.0f, 0.0f};  // swing / spin axis (local to the rest pose)
  float amplitude = 0.5f;            // swing: peak angle in radians
  float period = 2.0f;               // swing: seconds per full swing
  float speed = 1.0f;                // spin: radians per second; walk: metres per second
  std::vector<glm::vec3> path;       // walk: waypoints, looped (translations)
  float phase = 0.0f;                // seconds added to the clock
  // Rest pose, captured from the Transform when the component is added through make_animated().
  glm::vec3 rest_translation{0.0f};
  glm::quat rest_rotation{1.0f, 0.0f, 0.0f, 0.0f};
};

// Records the entity's current Transform as the rest pose and adds the component.
Animated& make_animated(Registry& registry, Entity e, Animated animation);
// Poses every Animated entity for absolute time `seconds` (deterministic: same time, same pose).
void update_animations(Registry& registry, float seconds);

}  // namespace engine
