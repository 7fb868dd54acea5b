#include "izb_corner_rays.hpp"

#include <cmath>

#include "shared/shadow_common.h"

namespace shadows::detail {

void set_ray_scales(gpu_shared::IzbParams& p, const glm::mat4& inverse_vp) {
  // The same arithmetic as camera_ray at any pixel corner (pixel_corner_points' x and y terms are zeros).
  const gpu_shared::HomogeneousRay h = gpu_shared::pixel_corner_points(glm::vec2(0.0f), glm::vec2(1.0f), inverse_vp);
  p.ray_scales = glm::vec4(gpu_shared::shared_divide(1.0f, h.near_point.w),
                           gpu_shared::shared_divide(1.0f, h.far_point.w), 0.0f, 0.0f);
}

// IZB_FLAG_BOUNDED_FIT: camera_ray at pixel corner (x, y) as an origin and a direction affine in x and
// y (with the inverse view-projection's w row free of x and y, each point's w is one constant), and
// bounds on how far rounding takes the build's rays and the fit's from them, in units of 2^-23 (twice
// float's unit roundoff, u): the build's point is four products summed (4u of their sizes) from a
// corrected NDC quotient (3u of the x and y columns), times 1 / w (u), and its direction the far point
// less the near one (u); the fit's ray is three float terms (2u, and u for the coefficients' own).
void set_corner_rays(gpu_shared::IzbParams& p, const glm::mat4& inverse_vp, VkExtent2D extent) {
  const glm::dmat4 m(inverse_vp);
  const double near_scale = p.ray_scales.x, far_scale = p.ray_scales.y;
  const double unit = std::ldexp(1.0, -23);
  const glm::dvec3 step_x = glm::dvec3(m[0]) * (2.0 / extent.width), step_y = glm::dvec3(m[1]) * (2.0 / extent.height);
  // Pixel corner (0, 0) is NDC (-1, -1); the near point at depth 1, the far one at 0.5 (pixel_corner_points).
  const glm::dvec3 origin = glm::dvec3(-m[0] - m[1] + m[2] + m[3]) * near_scale;
  const glm::dvec3 far_point = glm::dvec3(-m[0] - m[1] + 0.5 * m[2] + m[3]) * far_scale;
  const glm::dvec3 origin_x = step_x * near_scale, origin_y = step_y * near_scale;
  const glm::dvec3 direction = far_point - origin;
  const glm::dvec3 direction_x = step_x * (far_scale - near_scale), direction_y = step_y * (far_scale - near_scale);
  const double w = extent.width, h = extent.height;
  const double origin_size = glm::length(origin) + w * glm::length(origin_x) + h * glm::length(origin_y);
  const double direction_size = glm::length(direction) + w * glm::length(direction_x) + h * glm::length(direction_y);
  const double x_y = glm::length(glm::dvec3(m[0])) + glm::length(glm::dvec3(m[1]));
  const double near_terms = x_y + glm::length(glm::dvec3(m[2])) + glm::length(glm::dvec3(m[3]));
  const double far_terms = x_y + 0.5 * glm::length(glm::dvec3(m[2])) + glm::length(glm::dvec3(m[3]));
  const double build_origin = unit * (std::abs(near_scale) * (2.0 * near_terms + 1.5 * x_y) + 0.5 * origin_size);
  const double build_far = unit * (std::abs(far_scale) * (2.0 * far_terms + 1.5 * x_y) + 0.5 * (origin_size + direction_size));
  const double build_direction = build_origin + build_far + 0.5 * unit * direction_size;
  const double fit_origin = 1.5 * unit * origin_size, fit_direction = 1.5 * unit * direction_size;
  p.corner_ray_origin[0] = glm::vec4(glm::vec3(origin), float(build_origin + fit_origin));
  p.corner_ray_origin[1] = glm::vec4(glm::vec3(origin_x), float(origin_size));
  p.corner_ray_origin[2] = glm::vec4(glm::vec3(origin_y), 0.0f);
  p.corner_ray_direction[0] = glm::vec4(glm::vec3(direction), float(build_direction + fit_direction));
  p.corner_ray_direction[1] = glm::vec4(glm::vec3(direction_x), float(direction_size));
  p.corner_ray_direction[2] = glm::vec4(glm::vec3(direction_y), 0.0f);
}

}  // namespace shadows::detail
