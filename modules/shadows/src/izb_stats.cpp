#include "barriers.hpp"
#include "izb_stats.hpp"

#include "izb_batch.hpp"

#include <algorithm>

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

namespace {

// The most any record of a frame asked of the work lists and the pool.
struct IzbDemand {
  uint64_t records = 0, tile_pairs = 0, pairs = 0, nodes = 0;
  void add(const uint32_t* c) {
    records = std::max({records, uint64_t(c[gpu_shared::IZB_COUNTER_RECORDS]),
                        uint64_t(c[gpu_shared::IZB_COUNTER_RECORDS + 1]),
                        uint64_t(c[gpu_shared::IZB_COUNTER_LIT_RECORDS])});
    tile_pairs = std::max({tile_pairs, uint64_t(c[gpu_shared::IZB_COUNTER_TILE_PAIRS]),
                           uint64_t(c[gpu_shared::IZB_COUNTER_TILE_PAIRS + 1]),
                           uint64_t(c[gpu_shared::IZB_COUNTER_LIT_TILE_PAIRS])});
    pairs = std::max<uint64_t>(pairs, c[gpu_shared::IZB_COUNTER_PAIRS]);
    nodes = std::max(nodes, uint64_t(c[gpu_shared::IZB_COUNTER_NODES]));
  }
};

// One record's statistics from its counters.
Stats stats_from_counters(const IzbState& s, const uint32_t* c) {
  auto sharded = [&](uint32_t counter) {
    uint64_t sum = 0;
    for (uint32_t k = 0; k < gpu_shared::kIzbCounterShards; ++k)
      sum += c[gpu_shared::izb_shard_word(counter, k)];
    return sum;
  };
  Stats st{};
  st.shading_points = sharded(gpu_shared::IZB_COUNTER_SHADING_POINTS);
  st.lit_candidates = sharded(gpu_shared::IZB_COUNTER_CANDIDATES);
  const uint64_t requested = c[gpu_shared::IZB_COUNTER_NODES];
  st.node_pool_size = s.res.pool_size;
  st.nodes_inserted = std::min<uint64_t>(requested, s.res.pool_size);
  st.node_overflow = c[gpu_shared::IZB_COUNTER_OVERFLOW];
  st.overflow_pixels = c[gpu_shared::IZB_COUNTER_OVERFLOW_PIXELS];
  st.csm_culled = sharded(gpu_shared::IZB_COUNTER_CSM_CULLED);
  st.culling_rate = st.lit_candidates ? double(st.csm_culled) / double(st.lit_candidates) : 0.0;
  st.lit_culled = sharded(gpu_shared::IZB_COUNTER_LIT_CULLED);
  st.caster_triangles = s.casters.triangle_count;
  st.caster_triangles_listed = c[gpu_shared::IZB_COUNTER_LISTED_TRIANGLES];
  st.trace_fragments_before_cull = sharded(gpu_shared::IZB_COUNTER_FRAGMENTS);
  st.trace_fragments_after_cull = sharded(gpu_shared::IZB_COUNTER_FRAGMENTS_KEPT);
  st.triangle_tests = sharded(gpu_shared::IZB_COUNTER_TRIANGLE_TESTS);
  st.triangle_tests_per_pixel = st.lit_candidates ? double(st.triangle_tests) / double(st.lit_candidates) : 0.0;
  st.list_length_max = c[gpu_shared::IZB_COUNTER_LIST_MAX];
  st.nonempty_texels = c[gpu_shared::IZB_COUNTER_NONEMPTY];
  st.list_length_average =
      st.nonempty_texels ? double(c[gpu_shared::IZB_COUNTER_LIST_SUM]) / double(st.nonempty_texels) : 0.0;
  st.hardware_conservative = s.last.hardware;
  st.trace_choice = s.probes.trace.choice();
  if (s.last.csm) st.csm_choice = s.probes.csm.choice();
  st.lit_choice = s.probes.lit.choice();
  st.csm_run_choice = s.probes.csm_run.choice();
  st.tile_work_choice = s.probes.shape.choice();
  if (s.last.compute_trace) {
    st.trace_records = c[gpu_shared::IZB_COUNTER_RECORDS];
    st.trace_tile_pairs = c[gpu_shared::IZB_COUNTER_TILE_PAIRS];
    st.trace_pairs = c[gpu_shared::IZB_COUNTER_PAIRS];
  }
  return st;
}

// Grows the compute passes' work lists to what this frame asked for (trace, CSM or lit map,
// whichever more), and the pool for the next frame when this one overflowed (unless a fixed size
// was asked for).
void grow_to_demand(IzbState& s, const IzbDemand& demand, uint32_t slot) {
  IzbResources& r = s.res;
  auto grow = [](IzbWorkList& list, uint64_t asked) {
    if (asked > list.capacity) list.demand = uint64_t(double(asked) * 1.25);
  };
  const bool overflowed = demand.records > r.records.capacity || demand.tile_pairs > r.tile_pairs.capacity ||
                          demand.pairs > r.pairs.capacity || demand.nodes > r.pool_size;
  if (overflowed) s.probes.discard_pending(slot);  // a frame slowed by an overflow does not speak for its backend
  grow(r.records, demand.records);
  grow(r.tile_pairs, demand.tile_pairs);
  grow(r.pairs, demand.pairs);
}

}  // namespace

void record_izb_stats(IzbState& s, IzbBatch& batch) {
  // (The compute trace counts fragments before the cull as it bins.)
  Frame& frame = batch.frame();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_stats");
  if (!batch.plan().compute_trace) {
    select_record(s, batch.records.front());
    draw_raster_trace(s, frame, batch.records.front().raster, true, VK_COMPARE_OP_ALWAYS, false);
    pass_barrier(frame.ctx, cmd);
  }
  for_each_record(s, batch, [&](IzbRecord& r) {
    s.dispatch(cmd, *r.frame, s.p->list_stats, r.push, (s.res.resolution + 7) / 8, (s.res.resolution + 7) / 8);
  });
}

void record_counters_readback(IzbState& s, const Frame& frame, uint32_t slices) {
  ScopedGpuRegion region(s.ctx, frame.profiler, frame.cmd, "izb_readback");
  s.res.counters_readback.record_copy(frame, s.res.counters, s.res.counter_stride * slices,
                                      pass_shader_stages(s.ctx) | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                                      VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                      "izb counters readback", slices);
}

void read_izb_counters(IzbState& s, std::vector<Stats>& records, uint32_t slot) {
  s.csm->frame_completed(slot);
  const auto readbacks = s.res.counters_readback.take_records(slot);
  if (readbacks.empty()) return;
  IzbDemand demand;
  for (const void* readback : readbacks) {
    const auto* c = static_cast<const uint32_t*>(readback);
    records.push_back(stats_from_counters(s, c));
    demand.add(c);
  }
  grow_to_demand(s, demand, slot);
  Stats& last = records.back();
  for (uint32_t k = 0; k < records.size(); ++k) s.csm->note_yield(slot, k, records[k].culling_rate);
  s.csm->after_frame(last, slot);
  if (demand.nodes > s.res.pool_size) s.res.pool_demand = uint64_t(double(demand.nodes) * 1.25);
}

}  // namespace shadows::detail
