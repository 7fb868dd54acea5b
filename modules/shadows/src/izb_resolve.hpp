#pragma once
#include "frame.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// The exact overflow fallback for the pixels whose nodes did not fit the pool (izb_fallback.comp).
void record_overflow_fallback(IzbState& s, IzbBatch& batch);
// The resolve: the visibility masks into the shadow term, the hybrid's list or a debug view
// (izb_resolve.comp); skipped where the build and trace wrote the term themselves.
void record_izb_resolve(IzbState& s, IzbBatch& batch, bool hybrid);

}  // namespace shadows::detail
