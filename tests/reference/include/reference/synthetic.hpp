#pragma once
// Hand-built scenes and shading points whose shadows can be worked out on paper, so the reference
// can be checked (and other CPU tests can be written) without a GPU or the scene loaders.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>

#include "engine/core/components.hpp"
#include "reference/shading_points.hpp"

namespace reference {

// A rectangle in the plane y = `y` spanning [min_xz, max_xz], two triangles wound counter-clockwise
// seen from +y: (v0, v2, v1) holds the corner (max.x, min.z), (v0, v3, v2) the corner (min.x,
// max.z), where v0 = min corner, v1 = (max.x, min.z), v2 = max corner, v3 = (min.x, max.z).
std::shared_ptr<engine::MeshData> make_quad_y(float y, glm::vec2 min_xz, glm::vec2 max_xz);

// An entity with Mesh and a Transform whose world matrix is set directly (no transform system
// needed).
engine::Entity add_mesh_entity(engine::Registry& registry,
                               std::shared_ptr<const engine::MeshData> mesh,
                               const glm::mat4& world = glm::mat4(1.0f));

// inverse(view_proj) of an orthographic camera looking straight down -y: NDC x maps to world
// x = center.x + half_extent.x * ndc.x, NDC y (down) to z = center.y + half_extent.y * ndc.y, and
// reversed depth 1 (near) to y = near_y, 0 (far) to y = far_y.
glm::mat4 top_down_inv_view_proj(glm::vec2 center_xz, glm::vec2 half_extent, float near_y = 10.0f,
                                 float far_y = -10.0f);

// Every pixel covered by the point where the camera ray through its centre meets the plane
// (plane_point, plane_normal); the normal is stored as given.
ShadingPoints plane_shading_points(uint32_t width, uint32_t height, const glm::mat4& inv_view_proj,
                                   glm::vec3 plane_point, glm::vec3 plane_normal);

}  // namespace reference
