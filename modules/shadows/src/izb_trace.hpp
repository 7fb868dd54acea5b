#pragma once
#include <glm/glm.hpp>

#include "frame.hpp"
#include "izb_pipelines.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// What the raster trace draws with: the pipelines per caster set and the region of light space that
// holds every receiver (a caster wholly beside it is not drawn).
struct IzbRasterTrace {
  glm::mat4 receiver_region{0.0f};
  const IzbTracePipelines* opaque = nullptr;  // without the alpha-test code where some casters have it
  const IzbTracePipelines* alpha_tested = nullptr;
  bool alpha = false;  // some casters are alpha-tested (IZB_FLAG_ALPHA)
  bool hardware = false;
};
IzbRasterTrace prepare_raster_trace(IzbState& s, const Frame& frame, const IzbSettings& settings,
                                    const IzbPlan& plan, const glm::mat4& light_view);

// Draws the casters' conservative raster trace (or, count_only, only counts its fragments); with
// fill_depth the farthest node depths become the early depth test's first.
void draw_raster_trace(IzbState& s, Frame& frame, const IzbRasterTrace& trace, bool count_only, VkCompareOp compare,
                       bool fill_depth);

// The frustum trace: every caster triangle against the nodes of the texels it touches, as compute
// work (tile work, then one thread per surviving (triangle, texel) pair) or as the raster trace.
void record_frustum_trace(IzbState& s, IzbBatch& batch, const IzbSettings& settings);

}  // namespace shadows::detail
