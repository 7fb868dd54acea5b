#include "penumbra_mask.hpp"

#include <algorithm>
#include <cmath>

#include <shared/shadow_common.h>

namespace support {

float nearest_occluder(const reference::EmbreeTracer& tracer, const glm::vec3& origin, const glm::vec3& dir, float limit) {
  if (!tracer.occluded_within(origin, dir, limit)) return -1.0f;
  float lo = 0.0f, hi = limit;
  for (int i = 0; i < 20; ++i) {
    const float mid = 0.5f * (lo + hi);
    (tracer.occluded_within(origin, dir, mid) ? hi : lo) = mid;
  }
  return hi;
}

std::vector<uint8_t> sub_pixel_penumbra_mask(const reference::ShadingPoints& points,
                                             const std::vector<float>& hard_reference,
                                             const reference::EmbreeTracer& tracer, const glm::vec3& to_light,
                                             float tan_half_angle, float pixel_angle, float fraction,
                                             float reach_margin, int window) {
  const size_t n = points.pixel_count();
  // Each shadowed pixel's penumbra radius (world units, across the light).
  std::vector<float> radius(n, -1.0f);
  for (size_t i = 0; i < n; ++i) {
    if (!points.covered(i) || !points.faces(i, to_light) || !(hard_reference[i] >= 0.0f && hard_reference[i] < 0.5f))
      continue;
    const glm::vec3 p(points.position[i]);
    const glm::vec3 origin = gpu_shared::shadow_ray_origin(p, glm::vec3(points.normal[i]),
                                                           gpu_shared::shadow_ray_offset(p, points.eye));
    const float limit = 4.0f * (1.0f + glm::length(p - points.eye) + glm::length(p));
    const float height = nearest_occluder(tracer, origin, to_light, limit);
    // A shadowed point whose occluder the bisection cannot place may cast any penumbra: as wide as any.
    radius[i] = height > 0.0f ? height * tan_half_angle : 3.0e38f;
  }
  const auto across = [&](const glm::vec3& d) { return glm::length(d - glm::dot(d, to_light) * to_light); };
  std::vector<uint8_t> mask(n, 0);
  const int w = int(points.width), h = int(points.height);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = points.index(uint32_t(x), uint32_t(y));
      if (!points.covered(i) || !points.faces(i, to_light)) continue;
      const glm::vec3 p(points.position[i]);
      const float pixel_width = glm::length(p - points.eye) * pixel_angle;
      bool sharp = true;
      for (int qy = std::max(0, y - window); sharp && qy <= std::min(h - 1, y + window); ++qy)
        for (int qx = std::max(0, x - window); qx <= std::min(w - 1, x + window); ++qx) {
          const size_t q = points.index(uint32_t(qx), uint32_t(qy));
          if (radius[q] < fraction * pixel_width) continue;
          if (across(glm::vec3(points.position[q]) - p) > reach_margin * radius[q] + pixel_width) continue;
          sharp = false;
          break;
        }
      mask[i] = sharp ? 1 : 0;
    }
  return mask;
}

}  // namespace support
