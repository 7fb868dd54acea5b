#pragma once
#include "frame.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Known-lit culling: every caster triangle's nearest depth and plane over the texels it touches
// (or per tile for a caster covering the whole tile), which proves points lit before they enter a
// list. Binned over light-space tiles like the compute CSM, whose work lists it shares.
void record_lit_map(IzbState& s, IzbBatch& batch, const IzbSettings& settings);
// The last record's lit map, decoded (empty where it did not run).
LitMapSnapshot read_lit_map(IzbState& s);

}  // namespace shadows::detail
