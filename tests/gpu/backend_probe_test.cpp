// The raster/compute probe: both backends timed on the first frames of a configuration, the faster
// kept, and a configuration seen before decided at once (no second round of probe frames).
#include <cstdlib>
#include <optional>
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
  // Alternating, at least kFramesEach each, more (up to kMaxFramesEach) while a backend's last two
  // frames disagree (probe_settled).
  int raster = 0, compute = 0;
  PassBackend kept = PassBackend::Auto;
  for (size_t i = 0; i <= 2 * BackendProbe::kMaxFramesEach; ++i) {
    const PassBackend b = frame(first);
    if (probe.choice().reason != "probing") {
      kept = b;
      break;
    }
    (b == PassBackend::Raster ? raster : compute)++;
  }
  EXPECT_NE(kept, PassBackend::Auto) << "still probing after " << raster + compute << " frames";
  EXPECT_GE(raster, int(BackendProbe::kFramesEach));
  EXPECT_LE(raster, int(BackendProbe::kMaxFramesEach));
  EXPECT_GE(compute, int(BackendProbe::kFramesEach));
  EXPECT_LE(compute, int(BackendProbe::kMaxFramesEach));
  EXPECT_LE(std::abs(raster - compute), 1);  // taken in turn
  EXPECT_EQ(probe.choice().reason.rfind("auto: ", 0), 0u) << probe.choice().reason;
  EXPECT_EQ(frame(first), kept);

  frame(second);  // a new configuration probes afresh
  EXPECT_EQ(probe.choice().reason, "probing");
  EXPECT_EQ(frame(first), kept);  // the first one is remembered: decided at once
  EXPECT_EQ(probe.choice().reason.rfind("auto: ", 0), 0u) << probe.choice().reason;

  EXPECT_EQ(probe.pick(PassBackend::Compute, true, true, first, profiler), PassBackend::Compute);
  EXPECT_EQ(probe.choice().reason, "forced");
}

// The records of one frame under two configurations (the sun's and a local light's keys), the second
// picked twice (a point light's faces): each key keeps its own probe frames and decides, and every
// pick of a key within a frame gets that frame's choice.
TEST_F(GpuTest, BackendProbeDecidesForEachConfigurationOfAFrame) {
  engine::gpu::GpuProfiler profiler(*ctx_);
  BackendProbe probe("probed_pass");
  const uint64_t sun = 1, faces = 2;
  auto pick = [&](uint64_t key, uint64_t frame) {
    return probe.pick(PassBackend::Auto, true, true, key, profiler, 0, frame, 1);
  };
  std::optional<PassBackend> sun_kept, faces_kept;
  int frames = 0;
  for (uint64_t frame = 0; frame < 4 * BackendProbe::kMaxFramesEach && !(sun_kept && faces_kept); ++frame, ++frames) {
    const PassBackend s = pick(sun, frame);
    const bool sun_probing = probe.probing();
    const PassBackend first_face = pick(faces, frame);
    const bool faces_probing = probe.probing();
    EXPECT_EQ(pick(faces, frame), first_face) << "frame " << frame;
    EXPECT_EQ(probe.probing(), faces_probing);
    ctx_->immediate_submit([&](VkCommandBuffer cmd) {
      profiler.begin_frame(cmd);
      for (int record = 0; record < 3; ++record) {
        profiler.begin(cmd, "probed_pass");
        profiler.end(cmd, "probed_pass");
      }
    });
    profiler.collect();
    if (!sun_probing) sun_kept = s;
    if (!faces_probing) faces_kept = first_face;
  }
  EXPECT_TRUE(sun_kept.has_value()) << "the sun's key still probing after " << frames << " frames";
  EXPECT_TRUE(faces_kept.has_value()) << "the faces' key still probing after " << frames << " frames";
  EXPECT_LE(frames, int(2 * BackendProbe::kMaxFramesEach + 1));
}

// A GPU raising its clocks makes each probe frame faster than the last: the probe waits until each
// backend's last two frames agree, so the backend timed later is not taken as the faster for it.
TEST(BackendProbeSettle, WaitsUntilTheLastTwoFramesAgree) {
  using shadows::detail::probe_settled;
  EXPECT_FALSE(probe_settled({}));
  EXPECT_FALSE(probe_settled({1.0}));
  EXPECT_FALSE(probe_settled({1.75, 1.29}));         // still falling by a quarter
  EXPECT_TRUE(probe_settled({1.75, 0.310, 0.303}));  // the last two agree: the first does not count
  EXPECT_TRUE(probe_settled({0.303, 0.345}));        // within 15 %
  EXPECT_FALSE(probe_settled({0.303, 0.426}));
  EXPECT_TRUE(probe_settled({0.002, 0.011}));        // a short region: timestamp noise, not a trend
}

}  // namespace
