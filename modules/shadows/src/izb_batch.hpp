#pragma once
#include <vector>

#include "frame.hpp"
#include "izb_pipelines.hpp"
#include "izb_plan.hpp"
#include "izb_state.hpp"
#include "izb_trace.hpp"
#include "shared/izb.h"

namespace shadows::detail {

// One IZB record, planned: a light, or one face of a point light.
struct IzbRecord {
  Frame* frame = nullptr;
  IzbPlan plan;
  gpu_shared::IzbComputePush push{};
  gpu_shared::IzbParams params{};
  IzbRasterTrace raster;
  IzbPipelines* pipelines = nullptr;  // specialized for plan.flags
  uint32_t counter_slice = 0;         // IzbResources::counter_slice
  uint32_t grid_slice = 0;            // IzbResources::grid_slice
};

// The records recorded together: each step for every record, then the barrier after the step, so that
// a point light's faces' small dispatches run side by side instead of each draining the GPU. Its
// records share one plan's flags; the steps take their common choices from the first.
struct IzbBatch {
  std::vector<IzbRecord> records;
  Frame& frame() const { return *records.front().frame; }  // the command buffer, profiler and context
  const IzbPlan& plan() const { return records.front().plan; }
};

// What the passes recorded next bind: `r`'s slices and pipelines.
inline void select_record(IzbState& s, const IzbRecord& r) {
  s.res.counter_slice = r.counter_slice;
  s.res.grid_slice = r.grid_slice;
  s.p = r.pipelines;
}

// Calls fn(record) for each record of `batch`, selected.
template <typename Fn>
void for_each_record(IzbState& s, IzbBatch& batch, Fn&& fn) {
  for (IzbRecord& r : batch.records) {
    select_record(s, r);
    fn(r);
  }
}

}  // namespace shadows::detail
