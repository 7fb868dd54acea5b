#include "cascade_fit.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "light_space.hpp"

namespace shadows::detail {

CascadeFit fit_cascades(const View& view, const CascadeSettings& settings, const Aabb& casters) {
  CascadeFit fit;
  fit.count = std::clamp(settings.count, 1u, kMaxCascadeCount);
  const float near_plane = std::max(view.near_plane, 1e-3f);
  const float far_plane = std::max(settings.max_distance, near_plane * 1.01f);
  const float band = std::clamp(settings.blend_band, 0.0f, 0.5f);
  const float n = float(fit.count);
  fit.splits[0] = near_plane;
  for (uint32_t i = 1; i <= fit.count; ++i) {
    const float t = float(i) / n;
    const float uniform = near_plane + (far_plane - near_plane) * t;
    const float logarithmic = near_plane * std::pow(far_plane / near_plane, t);
    fit.splits[i] = glm::mix(uniform, logarithmic, std::clamp(settings.lambda, 0.0f, 1.0f));
  }
  fit.splits[fit.count] = far_plane;
  for (uint32_t c = 0; c < fit.count; ++c)
    fit.blend_start[c] = fit.splits[c + 1] - band * (fit.splits[c + 1] - fit.splits[c]);

  // Lateral distance of a slice corner per unit of view depth.
  const float corner = glm::length(view.tan_half_fov);
  const glm::vec3 forward = -glm::vec3(view.view[0][2], view.view[1][2], view.view[2][2]);

  fit.light_view = light_view_matrix(view.light_direction);
  float caster_top = -std::numeric_limits<float>::max();  // light-view z nearest the light
  if (casters.valid())
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 p((i & 1) ? casters.max.x : casters.min.x, (i & 2) ? casters.max.y : casters.min.y,
                        (i & 4) ? casters.max.z : casters.min.z);
      caster_top = std::max(caster_top, (fit.light_view * glm::vec4(p, 1.0f)).z);
    }

  const float size = float(std::max(settings.map_size, 16u));
  for (uint32_t c = 0; c < fit.count; ++c) {
    // The slice also covers the previous cascade's blend band, which samples this cascade too.
    const float slice_near = c == 0 ? fit.splits[0] : fit.blend_start[c - 1];
    const float slice_far = fit.splits[c + 1];
    // Smallest sphere around the slice's corners, centred on the view axis. It depends only on the
    // split distances and the lens, so its size never changes as the camera moves or turns.
    const float k = 1.0f + corner * corner;
    const float centre = std::min(0.5f * (slice_near + slice_far) * k, slice_far);
    const float r_near = std::hypot(centre - slice_near, slice_near * corner);
    const float r_far = std::hypot(slice_far - centre, slice_far * corner);
    // Rounded up so float noise in the inputs cannot change the texel size between frames.
    const float radius = std::ceil(std::max(r_near, r_far) * 64.0f) / 64.0f;
    const float texel = 2.0f * radius / size;
    const glm::vec3 centre_world = view.camera_position + forward * centre;
    glm::vec3 lc = glm::vec3(fit.light_view * glm::vec4(centre_world, 1.0f));
    // Whole-texel snapping: the grid only ever moves by entire texels, so static shadows don't crawl.
    lc.x = std::round(lc.x / texel) * texel;
    lc.y = std::round(lc.y / texel) * texel;
    // Depth: the sphere, extended toward the light to the highest caster; quantised coarsely so that
    // small camera motions leave the stored depths unchanged.
    const float q = texel * 64.0f;
    const float hi = std::ceil((std::max(lc.z + radius, caster_top) + texel) / q) * q;
    const float lo = std::floor((lc.z - radius - texel) / q) * q;
    const glm::mat4 proj = glm::orthoRH_ZO(lc.x - radius, lc.x + radius, lc.y - radius, lc.y + radius, -hi, -lo);
    fit.light_view_projection[c] = proj * fit.light_view;
    fit.radius[c] = radius;
    fit.texel_world[c] = texel;
    fit.depth_range[c] = hi - lo;
    fit.grid_origin[c] = glm::vec2(lc.x - radius, lc.y - radius);
  }
  return fit;
}

}  // namespace shadows::detail
