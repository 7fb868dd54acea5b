#pragma once
// The per-pixel input the reference shares with the GPU techniques: one shading point per pixel.
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace reference {

struct ShadingPoints {
  uint32_t width = 0;
  uint32_t height = 0;
  // World-space position; w = 1 where geometry covers the pixel, 0 for background.
  std::vector<glm::vec4> position;
  // Geometric normal (xyz, unit), oriented towards the camera; w as the G-buffer writes it (1 where
  // the point faces the light, gpu_shared::faces_light), read only when `facing_from_w` is set.
  std::vector<glm::vec4> normal;
  // Whether normal.w carries the G-buffer's light-facing decision (captured frames); otherwise
  // (synthetic points) a point faces the light when dot(normal.xyz, to_light) > 0.
  bool facing_from_w = false;
  // NDC (Vulkan: x, y in [-1,1], y down, reversed depth: 1 near, 0 far) to world. The 32-sample
  // mode needs it to place the μQuad samples exactly where the GPU places them.
  glm::mat4 inv_view_proj{1.0f};
  // The camera's position, in the points' coordinates: the shadow-ray offset grows with the distance
  // from it (gpu_shared::shadow_ray_offset).
  glm::vec3 eye{0.0f};

  // Pixel (x, y) lives at index y * width + x.
  size_t index(uint32_t x, uint32_t y) const { return size_t(y) * width + x; }
  size_t pixel_count() const { return size_t(width) * height; }
  bool covered(size_t i) const { return position[i].w > 0.5f; }
  bool faces(size_t i, const glm::vec3& to_light) const {
    return facing_from_w ? normal[i].w > 0.5f : glm::dot(glm::vec3(normal[i]), to_light) > 0.0f;
  }

  // Sizes both arrays for width x height with every pixel background.
  void resize(uint32_t w, uint32_t h) {
    width = w;
    height = h;
    position.assign(pixel_count(), glm::vec4(0.0f));
    normal.assign(pixel_count(), glm::vec4(0.0f));
  }
};

}  // namespace reference
