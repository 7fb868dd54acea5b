#pragma once
#include "frame.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Clears the counters every record starts from, visible to the passes after it.
void record_izb_reset(IzbState& s, const Frame& frame);
// Clears the grid's lists' heads (or counts) and farthest depths, with no barrier of its own: recorded
// at the light frustum's start, the fills run beside its passes, and the barrier after the light
// frustum orders them before the build.
void record_grid_reset(IzbState& s, const Frame& frame, const IzbPlan& plan);
// The IZB build: each pixel's node(s) into its texels' linked lists or, sorted, counted, prefix-summed
// and scattered into contiguous ranges (izb_build.comp, izb_scan.comp, izb_scatter.comp).
void record_izb_build(IzbState& s, Frame& frame, const IzbSettings& settings, const IzbPlan& plan,
                      const gpu_shared::IzbComputePush& push);

}  // namespace shadows::detail
