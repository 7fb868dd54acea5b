#include "engine/core/transform_system.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace engine {

namespace {
enum class Visit : uint8_t { Pending, OnPath, Done };

bool has_transform_parent(const Registry& registry, const Transform& t) {
  // A destroyed or transform-less parent makes the entity a root rather than an error: scenes are
  // edited at run time and dangling links must not stop a frame.
  return t.parent.valid() && registry.has<Transform>(t.parent);
}
}  // namespace

void update_world_transforms(Registry& registry) {
  const std::vector<Entity> entities = registry.view<Transform>();
  uint32_t max_index = 0;
  for (Entity e : entities) max_index = std::max(max_index, e.index);
  std::vector<Visit> state(entities.empty() ? 0 : size_t(max_index) + 1, Visit::Pending);

  std::vector<Entity> path;
  for (Entity start : entities) {
    if (state[start.index] == Visit::Done) continue;
    // Walk up to the first resolved ancestor or root, then resolve top-down. Iterative so that deep
    // hierarchies cannot overflow the stack.
    path.clear();
    Entity current = start;
    for (;;) {
      state[current.index] = Visit::OnPath;
      path.push_back(current);
      Transform& t = registry.get<Transform>(current);
      if (!has_transform_parent(registry, t)) break;
      const Visit parent_state = state[t.parent.index];
      if (parent_state == Visit::Done) break;
      if (parent_state == Visit::OnPath) {
        // The link closing the loop is cut, so the result is stable from frame to frame.
        t.parent = kNullEntity;
        break;
      }
      current = t.parent;
    }
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      Transform& t = registry.get<Transform>(*it);
      const glm::mat4 local = t.local_matrix();
      t.world = has_transform_parent(registry, t) ? registry.get<Transform>(t.parent).world * local : local;
      state[it->index] = Visit::Done;
    }
  }
}

void update_camera(Registry& registry, Entity camera, float aspect) {
  const Transform& t = registry.get<Transform>(camera);
  Camera& c = registry.get<Camera>(camera);
  c.view = glm::inverse(t.world);
  if (!(aspect > 0.0f) || !std::isfinite(aspect)) aspect = 1.0f;
  // Reversed Z (near maps to depth 1, far to 0) spends float precision where the distance is large.
  c.projection = glm::perspectiveRH_ZO(c.vertical_fov, aspect, c.far_plane, c.near_plane);
  // Vulkan clip space has +y pointing down the image.
  c.projection[1][1] *= -1.0f;
}

void place_camera(Registry& registry, Entity camera, const glm::vec3& eye, const glm::vec3& target) {
  Transform& t = registry.get<Transform>(camera);
  t.translation = eye;
  const glm::vec3 to_target = target - eye;
  const float distance = glm::length(to_target);
  if (distance > 1e-12f && std::isfinite(distance)) {
    const glm::vec3 forward = to_target / distance;
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    // Looking (almost) straight up or down leaves +Y parallel to the view direction; -Z then puts
    // the scene's "north" at the top of the image.
    if (std::abs(glm::dot(forward, up)) > 0.999f) up = glm::vec3(0.0f, 0.0f, -1.0f);
    const glm::vec3 right = glm::normalize(glm::cross(forward, up));
    const glm::vec3 true_up = glm::cross(right, forward);
    const glm::mat3 basis{right, true_up, -forward};  // camera looks down its local -Z
    t.rotation = glm::normalize(glm::quat_cast(basis));
  }
  // A root camera's world matrix is its local one, so keep it usable before the next transform pass.
  if (!has_transform_parent(registry, t)) t.world = t.local_matrix();
}

}  // namespace engine
