#pragma once
#include "frame.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// The compute CSM's per-caster-draw flags: whether each draw enters the CSM this frame.
void upload_csm_draw_flags(IzbState& s, const Frame& frame);
// The conservative shadow map prepass (CsmPass), as raster work or as the IZB's compute tile work.
void record_csm_prepass(IzbState& s, IzbBatch& batch, const IzbSettings& settings, bool collect_stats);
// The last record's CSM depths (empty where it did not run).
CsmSnapshot read_csm(IzbState& s);

}  // namespace shadows::detail
