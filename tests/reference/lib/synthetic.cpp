#include "reference/synthetic.hpp"

#include <shared/shadow_common.h>

namespace reference {

std::shared_ptr<engine::MeshData> make_quad_y(float y, glm::vec2 min_xz, glm::vec2 max_xz) {
  auto mesh = std::make_shared<engine::MeshData>();
  mesh->name = "quad";
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  mesh->vertices = {
      {glm::vec3(min_xz.x, y, min_xz.y), up, glm::vec2(0.0f, 0.0f)},
      {glm::vec3(max_xz.x, y, min_xz.y), up, glm::vec2(1.0f, 0.0f)},
      {glm::vec3(max_xz.x, y, max_xz.y), up, glm::vec2(1.0f, 1.0f)},
      {glm::vec3(min_xz.x, y, max_xz.y), up, glm::vec2(0.0f, 1.0f)},
  };
  mesh->indices = {0, 2, 1, 0, 3, 2};
  // Set here rather than through compute_bounds so this stays free of engine_core's sources.
  mesh->bounds.min = glm::vec3(min_xz.x, y, min_xz.y);
  mesh->bounds.max = glm::vec3(max_xz.x, y, max_xz.y);
  return mesh;
}

engine::Entity add_mesh_entity(engine::Registry& registry,
                               std::shared_ptr<const engine::MeshData> mesh,
                               const glm::mat4& world) {
  const engine::Entity e = registry.create();
  registry.emplace<engine::Mesh>(e, engine::Mesh{std::move(mesh)});
  engine::Transform t;
  t.world = world;
  registry.emplace<engine::Transform>(e, t);
  return e;
}

glm::mat4 top_down_inv_view_proj(glm::vec2 center_xz, glm::vec2 half_extent, float near_y,
                                 float far_y) {
  glm::mat4 m(0.0f);
  m[0] = glm::vec4(half_extent.x, 0.0f, 0.0f, 0.0f);   // ndc x -> world x
  m[1] = glm::vec4(0.0f, 0.0f, half_extent.y, 0.0f);   // ndc y -> world z
  m[2] = glm::vec4(0.0f, near_y - far_y, 0.0f, 0.0f);  // depth -> world y
  m[3] = glm::vec4(center_xz.x, far_y, center_xz.y, 1.0f);
  return m;
}

ShadingPoints plane_shading_points(uint32_t width, uint32_t height, const glm::mat4& inv_view_proj,
                                   glm::vec3 plane_point, glm::vec3 plane_normal) {
  ShadingPoints sp;
  sp.resize(width, height);
  sp.inv_view_proj = inv_view_proj;
  const glm::vec2 viewport{float(width), float(height)};
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      const glm::vec3 p =
          gpu_shared::micro_quad_sample(glm::vec2(float(x), float(y)), glm::vec2(0.5f), viewport,
                                        inv_view_proj, plane_point, plane_normal);
      sp.position[sp.index(x, y)] = glm::vec4(p, 1.0f);
      sp.normal[sp.index(x, y)] = glm::vec4(plane_normal, 0.0f);
    }
  }
  return sp;
}

}  // namespace reference
