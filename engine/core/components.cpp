#include "engine/core/components.hpp"

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
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 corner{(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z};
    out.extend(glm::vec3(m * glm::vec4(corner, 1.0f)));
  }
  return out;
}

bool Aabb::outside_clip(const glm::mat4& clip, const glm::vec4& ndc, float min_w) const {
  if (!valid()) return false;  // unknown extent: never culled
  // Bit k set: every corner so far lies beyond plane k (left, right, bottom, top, near).
  uint32_t beyond_all = 0x1f;
  for (int i = 0; i < 8 && beyond_all; ++i) {
    const glm::vec4 c = clip * glm::vec4((i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z, 1.0f);
    const uint32_t beyond = (c.x < ndc.x * c.w ? 1u : 0u) | (c.x > ndc.z * c.w ? 2u : 0u) |
                            (c.y < ndc.y * c.w ? 4u : 0u) | (c.y > ndc.w * c.w ? 8u : 0u) | (c.w < min_w ? 16u : 0u);
    beyond_all &= beyond;
  }
  return beyond_all != 0;
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

uint32_t alpha_threshold(float cutoff, float scale) {
  for (uint32_t byte = 0; byte < 256; ++byte)
    if (scale * float(byte) / 255.0f >= cutoff) return byte;
  return 256;
}

}  // namespace engine
