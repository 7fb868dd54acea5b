#pragma once
#include "cascades_pass.hpp"
#include "frame.hpp"
#include "izb_resources.hpp"
#include "izb_state.hpp"

namespace shadows::detail {

// Hybrid: the IZB's resolve lists the pixels that take some of the cascades' filtered term; the
// cascades filter only those into the soft term, and the blend mixes it into the shadow term
// (izb_hybrid_blend.comp), then restores the soft term to "not filtered".
PixelList izb_hybrid_list(const IzbResources& res);
void record_hybrid_blend(IzbState& s, Frame& frame);
// Hybrid with a sun of some size, after the IZB's term and occluder heights: the penumbrae
// (izb_penumbra.comp) into the shadow term.
void record_hybrid_penumbra(IzbState& s, Frame& frame, bool step_timings);

}  // namespace shadows::detail
