#include "engine/core/animation.hpp"

#include <cmath>

#include <glm/gtc/quaternion.hpp>

namespace engine {

Animated& make_animated(Registry& registry, Entity e, Animated animation) {
  if (const Transform* t = registry.try_get<Transform>(e)) {
    animation.rest_translation = t->translation;
    animation.rest_rotation = t->rotation;
  }
  if (glm::length(animation.axis) < 1e-6f) animation.axis = glm::vec3(0.0f, 1.0f, 0.0f);
  animation.axis = glm::normalize(animation.axis);
  return registry.emplace<Animated>(e, std::move(animation));
}

void update_animations(Registry& registry, float seconds) {
  registry.each<Animated, Transform>([&](Entity, Animated& a, Transform& t) {
    const float time = seconds + a.phase;
    switch (a.kind) {
      case Animated::Kind::Swing: {
        const float angle = a.amplitude * std::sin(2.0f * 3.14159265f * time / std::max(a.period, 1e-3f));
        t.rotation = a.rest_rotation * glm::angleAxis(angle, a.axis);
        break;
      }
      case Animated::Kind::Spin:
        t.rotation = a.rest_rotation * glm::angleAxis(std::fmod(a.speed * time, 6.2831853f), a.axis);
        break;
      case Animated::Kind::Walk: {
        if (a.path.size() < 2) break;
        float total = 0.0f;
        for (size_t i = 0; i < a.path.size(); ++i) total += glm::length(a.path[(i + 1) % a.path.size()] - a.path[i]);
        if (total <= 0.0f) break;
        float s = std::fmod(a.speed * time, total);
        if (s < 0.0f) s += total;
        for (size_t i = 0; i < a.path.size(); ++i) {
          const glm::vec3 p0 = a.path[i], p1 = a.path[(i + 1) % a.path.size()];
          const float len = glm::length(p1 - p0);
          if (s > len && i + 1 < a.path.size()) {
            s -= len;
            continue;
          }
          const glm::vec3 dir = len > 0.0f ? (p1 - p0) / len : glm::vec3(0.0f, 0.0f, 1.0f);
          t.translation = p0 + dir * std::min(s, len);
          t.translation.y += 0.05f * std::abs(std::sin(time * 6.0f));  // a little bob per step
          // Face the walking direction (the model's +z is its front).
          t.rotation = glm::angleAxis(std::atan2(dir.x, dir.z), glm::vec3(0.0f, 1.0f, 0.0f)) * a.rest_rotation;
          break;
        }
        break;
      }
    }
  });
}

}  // namespace engine
