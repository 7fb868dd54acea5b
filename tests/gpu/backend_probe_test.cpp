// The raster/compute probe: both backends timed on the first frames of a configuration, the faster
// kept, and a configuration seen before decided at once (no second round of probe frames).
#include <string>

#include "backend_probe.hpp"
#include "gpu/profiler.hpp"
#include "gpu_fixture.hpp"

namespace {

using shadows::PassBackend;
using shadows::detail::BackendProbe;

TEST_F(GpuTest, BackendProbeTimesBothThenRemembersEachConfiguration) {
  engine::gpu::GpuProfiler profiler(*ctx_);
  BackendProbe probe("probed_pass");
  // One frame: the probe picks, the pass's region is recorded and timed.
  auto frame = [&](uint64_t key) {
    const PassBackend b = probe.pick(PassBackend::Auto, true, true, key, profiler);
    ctx_->immediate_submit([&](VkCommandBuffer cmd) {
      profiler.begin_frame(cmd);
      profiler.begin(cmd, "probed_pass");
      profiler.end(cmd, "probed_pass");
    });
    profiler.collect();
    return b;
  };
  const uint64_t first = 1, second = 2;
  int raster = 0, compute = 0;
  for (size_t i = 0; i < 2 * BackendProbe::kFramesEach; ++i) {
    (frame(first) == PassBackend::Raster ? raster : compute)++;
    EXPECT_EQ(probe.choice().reason, "probing");
  }
  EXPECT_EQ(raster, int(BackendProbe::kFramesEach));
  EXPECT_EQ(compute, int(BackendProbe::kFramesEach));
  const PassBackend kept = frame(first);
  EXPECT_EQ(probe.choice().reason.rfind("auto: ", 0), 0u) << probe.choice().reason;
  EXPECT_EQ(frame(first), kept);

  frame(second);  // a new configuration probes afresh
  EXPECT_EQ(probe.choice().reason, "probing");
  EXPECT_EQ(frame(first), kept);  // the first one is remembered: decided at once
  EXPECT_EQ(probe.choice().reason.rfind("auto: ", 0), 0u) << probe.choice().reason;

  EXPECT_EQ(probe.pick(PassBackend::Compute, true, true, first, profiler), PassBackend::Compute);
  EXPECT_EQ(probe.choice().reason, "forced");
}

}  // namespace
