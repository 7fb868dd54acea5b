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
// The IZB build: each pixel's node(s) into its texels' linked lists or, sorted, counted, prefix-summed
// and scattered into contiguous ranges (izb_build.comp, izb_scan.comp, izb_scatter.comp).
void record_izb_build(IzbState& s, IzbBatch& batch, const IzbSettings& settings);

}  // namespace shadows::detail
