#pragma once
// Which pixels the sun's penumbrae leave sharp: where no penumbra wider than part of a pixel reaches,
// the hybrid must keep the IZB's exact term (shadows::Settings, the hybrid's penumbrae).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <shared/izb.h>

#include "reference/embree_tracer.hpp"
#include "reference/shading_points.hpp"

namespace support {

// For each covered pixel facing the light: 1 where every penumbra that can reach it is narrower than
// `fraction` of its width, else 0. A shadowed pixel (`hard_reference` < 0.5, the 1 spp reference of the
// same points) casts a penumbra of radius h tan(a) across the light, h its nearest occluder's height
// above it along the light (Embree, from the shadow ray's origin; unbounded where the bisection
// finds none within its limit), a the sun's angular radius
// (`tan_half_angle`); it reaches the pixels within that radius, widened by `reach_margin` times and
// a pixel, of its pixel within `window` pixels (by default as far as the hybrid's filter reaches,
// gpu_shared::kPenumbraMaxRadius, and a pixel either side). A pixel's width at a point is its distance from the eye
// times `pixel_angle` (2 tan(vertical fov / 2) / height).
std::vector<uint8_t> sub_pixel_penumbra_mask(const reference::ShadingPoints& points,
                                             const std::vector<float>& hard_reference,
                                             const reference::EmbreeTracer& tracer, const glm::vec3& to_light,
                                             float tan_half_angle, float pixel_angle, float fraction = 0.4f,
                                             float reach_margin = 1.25f,
                                             int window = int(gpu_shared::kPenumbraMaxRadius) + 2);

// The nearest occluder's distance along `dir` (unit) from `origin`, by bisection on
// EmbreeTracer::occluded_within (within 2^-20 of `limit`); -1 where nothing lies within `limit`.
float nearest_occluder(const reference::EmbreeTracer& tracer, const glm::vec3& origin, const glm::vec3& dir, float limit);

}  // namespace support
