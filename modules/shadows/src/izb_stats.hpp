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
void record_izb_stats(IzbState& s, Frame& frame, const IzbPlan& plan, const IzbRasterTrace& raster,
                      const gpu_shared::IzbComputePush& push);
// The counters into this frame-in-flight slot's readback, read by after_frame.
void record_counters_readback(IzbState& s, const Frame& frame);
// Turns the slot's counters (one readback per IZB record) into statistics and grows the work lists
// and the node pool to what the records asked for.
void read_izb_counters(IzbState& s, std::vector<Stats>& records, uint32_t slot);

}  // namespace shadows::detail
