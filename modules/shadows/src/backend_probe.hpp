#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "gpu/profiler.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Chooses raster or compute for one pass under PassBackend::Auto by timing both: the first frames
// alternate the two, reading the pass's GPU region of the previous frame from the profiler, then the
// faster (by its best probe frame) is kept for that configuration key, once each backend's last two
// frames agree (probe_settled), or after kMaxFramesEach: a GPU that has just woken runs its first
// frames slower, each faster than the last, which favours the backend timed later in the alternation
// (H200, contact 4K, the first run after idling: the lit map's probe timed 1.29 and 1.75 ms for ways
// that settle at 0.30 and 0.43; in two runs of four it kept the slower). Each key's probe is
// remembered, so a configuration seen before (dynamic resolution stepping back and forth between
// sizes) takes its decision at once instead of probing again: a probe frame of the slower backend is
// a visible hitch on a CPU device.
class BackendProbe {
 public:
  static constexpr size_t kFramesEach = 2;
  static constexpr size_t kMaxFramesEach = 4;
  static constexpr size_t kRememberedKeys = 64;  // beyond this many configurations, probing starts afresh

  explicit BackendProbe(std::string region) : regions_{std::move(region)} {}
  // A choice between two ways of doing the same work, timed by the sum of several regions (every
  // occurrence in the frame), named `names` (for Raster and Compute) in choice().
  BackendProbe(std::vector<std::string> regions, std::array<std::string, 2> names)
      : regions_(std::move(regions)), names_(std::move(names)) {}
  BackendProbe(const BackendProbe&) = delete;  // probe_ points into probes_
  BackendProbe& operator=(const BackendProbe&) = delete;
  // This frame's backend. `key` identifies what the timing depends on (sizes, scene, mode).
  // `frame_index` (View::frame_index) and `frame_slots` (frames in flight) tell the records of one
  // frame apart: every pick of a key within a frame gets that frame's choice (a point light's six
  // faces), keys picked in the same frame each keep their own probe frames (the sun and a local
  // light), and a probe frame's time is read only from the frame that ran it. Without them each
  // call is a frame of its own.
  PassBackend pick(PassBackend requested, bool raster_available, bool compute_available, uint64_t key,
                   const engine::gpu::GpuProfiler& profiler, uint32_t frame_slot = 0,
                   std::optional<uint64_t> frame_index = std::nullopt, uint32_t frame_slots = 1);
  const Stats::BackendChoice& choice() const { return choice_; }
  // Whether the last pick was a probe frame (no decision yet for its key).
  bool probing() const { return probing_; }
  // The frame just recorded is not representative (e.g. its work lists overflowed and grow for the
  // next frame): its time is not taken, and the probe runs that backend again.
  void discard_pending(uint32_t frame_slot) {
    for (auto& [key, probe] : probes_)
      if (frame_slot < probe.pending.size()) probe.pending[frame_slot].reset();
  }

 private:
  std::vector<std::string> regions_;
  std::array<std::string, 2> names_ = {"raster", "compute"};
  bool probing_ = false;
  uint64_t key_ = ~uint64_t(0);
  uint64_t calls_ = 0;  // a frame index for picks given none
  // A probe frame's backend and frame index, its time not yet read.
  struct PendingFrame {
    PassBackend backend;
    uint64_t frame;
  };
  struct Probe {
    std::vector<double> samples[2];  // raster, compute
    std::optional<PassBackend> decided;
    // Per frame-in-flight slot: the probe frame that slot last ran with this key. The profiler passed
    // to pick() holds the times of the frame that last used the slot.
    std::vector<std::optional<PendingFrame>> pending;
    // This key's last pick, given again to the frame's other records.
    std::optional<uint64_t> last_frame;
    PassBackend last_backend = PassBackend::Compute;
    Stats::BackendChoice last_choice;
    bool last_probing = false;
  };
  PassBackend decide(PassBackend requested, bool raster_available, bool compute_available,
                     const engine::gpu::GpuProfiler& profiler, uint32_t frame_slot, uint64_t frame_index,
                     uint32_t frame_slots);
  std::map<uint64_t, Probe> probes_;
  Probe* probe_ = nullptr;  // the current key's
  Stats::BackendChoice choice_;
};

// Whether a backend's probe frames have settled: its last two times agree within 15 % (or 0.02 ms,
// the noise of a short region's timestamps).
bool probe_settled(const std::vector<double>& samples);

// Mixes values into a configuration key.
uint64_t mix_key(uint64_t key, uint64_t value);

}  // namespace shadows::detail
