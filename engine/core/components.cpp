#include "engine/core/components.hpp"

#include <shared/bounds.h>
#include <shared/material.h>

namespace engine {

glm::mat4 rebased(const glm::mat4& world, const glm::dvec3& shift) {
  glm::mat4 m = world;
  m[3] = glm::vec4(glm::vec3(glm::dvec3(world[3]) + shift), world[3].w);
  return m;
}

glm::mat4 Transform::local_matrix() const {
  // T * R * S built directly: scale the rotation's basis columns, then set the translation column.
  glm::mat4 m = glm::mat4_cast(glm::normalize(rotation));
  m[0] *= scale.x;
  m[1] *= scale.y;
  m[2] *= scale.z;
  m[3] = glm::vec4(translation, 1.0f);
  return m;
}

Aabb Aabb::transformed(const glm::mat4& m) const {
  Aabb out;
  if (!valid()) return out;
  // Rotations make any corner a potential extreme, so all eight are transformed.
  for (uint32_t i = 0; i < 8; ++i) out.extend(glm::vec3(m * glm::vec4(gpu_shared::box_corner(min, max, i), 1.0f)));
  return out;
}

bool Aabb::outside_clip(const glm::mat4& clip, const glm::vec4& ndc, float min_w) const {
  return valid() && gpu_shared::box_outside_clip(clip, min, max, ndc, min_w);  // unknown extent: never culled
}

void MeshData::compute_bounds() {
  bounds = Aabb{};
  for (const Vertex& v : vertices) bounds.extend(v.position);
}

}  // namespace engine

namespace engine {

bool alpha_tested(const Material& m) { return m.alpha_mode != AlphaMode::Opaque; }

uint32_t alpha_threshold(const Material& m) {
  if (!alpha_tested(m)) return 0;
  return alpha_threshold(m.alpha_mode == AlphaMode::Blend ? 0.5f : m.alpha_cutoff, m.base_color.a);
}

uint32_t alpha_threshold(float cutoff, float scale) { return gpu_shared::alpha_threshold_byte(cutoff, scale); }

}  // namespace engine
