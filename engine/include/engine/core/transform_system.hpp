#pragma once
#include "engine/core/components.hpp"

namespace engine {
// Resolves Transform::world for every entity, parents before children (cycles are broken).
void update_world_transforms(Registry& registry);
// Updates Camera::view/projection from the camera entity's world transform.
void update_camera(Registry& registry, Entity camera, float aspect);
// Look-at helper: positions `camera`'s Transform at `eye` looking at `target` (+Y up).
void place_camera(Registry& registry, Entity camera, const glm::vec3& eye, const glm::vec3& target);
}  // namespace engine
