#pragma once
#include <cstdint>
#include <vector>

#include "frame.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "izb_trace.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Statistics only (excluded from the technique's total): fragments before depth culling and the
// lists' lengths.
void record_izb_stats(IzbState& s, IzbBatch& batch);
// The counters' first `slices` slices (a record's, or a point light's faces') into this frame-in-flight
// slot's readback, read by after_frame.
void record_counters_readback(IzbState& s, const Frame& frame, uint32_t slices);
// Turns the slot's counters (one readback per IZB record) into statistics and grows the work lists
// and the node pool to what the records asked for.
void read_izb_counters(IzbState& s, std::vector<Stats>& records, uint32_t slot);

}  // namespace shadows::detail
