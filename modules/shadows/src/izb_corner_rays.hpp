#pragma once
#include <glm/glm.hpp>
#include <vulkan/vulkan.h>

#include "shared/izb.h"

namespace shadows::detail {

// The 32 spp fit's camera rays (IZB_FLAG_CONSTANT_RAY_W, IZB_FLAG_BOUNDED_FIT): every camera ray's
// points share their w, so the μQuad corners take 1 / w from `p.ray_scales`, computed here with the
// same arithmetic as camera_ray at any pixel corner.
void set_ray_scales(gpu_shared::IzbParams& p, const glm::mat4& inverse_vp);
// Pixel corner rays as an origin and a direction affine in x and y, with bounds on what rounding
// moves them by, so the fit bounds each μQuad from corners made in fast arithmetic.
void set_corner_rays(gpu_shared::IzbParams& p, const glm::mat4& inverse_vp, VkExtent2D extent);

}  // namespace shadows::detail
