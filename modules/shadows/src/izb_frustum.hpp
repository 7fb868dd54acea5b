#pragma once
#include <cstdint>

#include <glm/glm.hpp>

#include "frame.hpp"
#include "izb_batch.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// The light frustum fit's workgroups over the view (izb_fit.comp).
inline uint32_t fit_columns(uint32_t width) {
  return (width + gpu_shared::kIzbFitBlockWidth - 1) / gpu_shared::kIzbFitBlockWidth;
}
inline uint32_t fit_rows(uint32_t height) {
  return (height + gpu_shared::kIzbFitBlockHeight - 1) / gpu_shared::kIzbFitBlockHeight;
}

// The CPU side of the light frustum: the light's view and the casters' depth range along it (for a
// spot light, its cone's half-angle too). The GPU fits the grid's other two axes (izb_fit.comp).
struct IzbLightView {
  glm::mat4 light_view{1.0f};
  float near_depth = 0.0f, far_depth = 1.0f;
  float tan_half_angle = 0.0f;
};
IzbLightView izb_light_view(const Frame& frame);

// The record's IzbParams (record_izb_reset writes them in the command stream).
gpu_shared::IzbParams izb_params(IzbState& s, const Frame& frame, const IzbSettings& settings, const IzbPlan& plan,
                                 const IzbLightView& light);

// GPU light-frustum fit (a per-block reduction whose last workgroup fits the grid and culls the
// caster draws by their world bounds), then the caster triangles into grid space.
void record_light_frustum(IzbState& s, IzbBatch& batch, const IzbSettings& settings);

}  // namespace shadows::detail
