#pragma once
#include "frame.hpp"
#include "izb_batch.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Writes each record's parameters and clears what it starts from, in one run of transfers: the
// counters, and the lists' heads or counts and the farthest depths unless the fit empties those
// (IzbPlan::fit_clears_grid).
void record_izb_reset(IzbState& s, IzbBatch& batch);
// A point light's faces (IZB_FLAG_FACE_TILES; on a CPU device a spot light's), before the first
// face's build: the six tile lists and the term of the points no face reaches. Recorded after the
// reset (which empties the lists) with no barrier of its own: the light frustum's steps run beside it,
// and the barrier after them makes its writes visible to the build.
void record_face_tiles(IzbState& s, IzbBatch& batch);
// The IZB build: each pixel's node(s) into its texels' linked lists or, sorted, counted, prefix-summed
// and scattered into contiguous ranges (izb_build.comp, izb_scan.comp, izb_scatter.comp).
void record_izb_build(IzbState& s, IzbBatch& batch, const IzbSettings& settings);

}  // namespace shadows::detail
