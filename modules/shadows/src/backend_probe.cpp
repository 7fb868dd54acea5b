#include "backend_probe.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace shadows::detail {

uint64_t mix_key(uint64_t key, uint64_t value) {
  key ^= value + 0x9e3779b97f4a7c15ull + (key << 6) + (key >> 2);
  return key;
}

bool probe_settled(const std::vector<double>& samples) {
  if (samples.size() < 2) return false;
  const double a = samples[samples.size() - 1], b = samples[samples.size() - 2];
  return std::abs(a - b) <= std::max(0.15 * std::max(a, b), 0.02);
}

namespace {
double best(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }
size_t slot(PassBackend b) { return b == PassBackend::Compute ? 1 : 0; }
}  // namespace

PassBackend BackendProbe::pick(PassBackend requested, bool raster_available, bool compute_available, uint64_t key,
                               const engine::gpu::GpuProfiler& profiler, uint32_t frame_slot,
                               std::optional<uint64_t> frame_index, uint32_t frame_slots) {
  const uint64_t frame = frame_index ? *frame_index : ++calls_;
  if (key != key_ || !probe_) {
    key_ = key;
    if (probes_.size() >= kRememberedKeys && !probes_.count(key)) probes_.clear();
    probe_ = &probes_[key];
  }
  Probe& p = *probe_;
  if (p.last_frame == frame) {
    choice_ = p.last_choice;
    probing_ = p.last_probing;
    return p.last_backend;
  }
  p.last_backend = decide(requested, raster_available, compute_available, profiler, frame_slot, frame,
                          frame_index ? frame_slots : 1u);
  p.last_frame = frame;
  p.last_choice = choice_;
  p.last_probing = probing_;
  return p.last_backend;
}

PassBackend BackendProbe::decide(PassBackend requested, bool raster_available, bool compute_available,
                                 const engine::gpu::GpuProfiler& profiler, uint32_t frame_slot, uint64_t frame_index,
                                 uint32_t frame_slots) {
  if (probe_->pending.size() <= frame_slot) probe_->pending.resize(frame_slot + 1);
  std::optional<PendingFrame>& pending = probe_->pending[frame_slot];
  auto& samples = probe_->samples;
  auto& decided = probe_->decided;
  // Only whole frames count: the regions of the frame that last used this slot (collected in the
  // profiler's segment of the same index: the host's frame N uses slot and segment N % F), if that was
  // the probe frame (a key not picked since, or another configuration in between, left it stale).
  if (pending && pending->frame + frame_slots == frame_index) {
    double total = 0.0;
    bool seen = false;
    for (const auto& [name, ms] : profiler.last_frame_of_slot(frame_slot))
      if (std::find(regions_.begin(), regions_.end(), name) != regions_.end()) {
        total += ms;
        seen = true;
      }
    if (seen) samples[slot(pending->backend)].push_back(total);
  }
  pending.reset();
  choice_.raster_ms = best(samples[0]);
  choice_.compute_ms = best(samples[1]);
  probing_ = false;
  const std::string& raster = names_[0];
  const std::string& compute = names_[1];
  auto use = [&](PassBackend b, std::string reason) {
    choice_.backend = names_[slot(b)];
    choice_.reason = std::move(reason);
    return b;
  };
  if (requested != PassBackend::Auto) return use(requested, "forced");
  if (!raster_available) return use(PassBackend::Compute, "only " + compute + " available");
  if (!compute_available) return use(PassBackend::Raster, "only " + raster + " available");
  if (!profiler.enabled()) return use(PassBackend::Compute, "no GPU timestamps to probe with: " + compute);
  const bool enough = samples[0].size() >= kFramesEach && samples[1].size() >= kFramesEach;
  const bool settled = probe_settled(samples[0]) && probe_settled(samples[1]);
  const bool exhausted = samples[0].size() >= kMaxFramesEach && samples[1].size() >= kMaxFramesEach;
  if (!decided && enough && (settled || exhausted)) {
    decided = choice_.compute_ms <= choice_.raster_ms ? PassBackend::Compute : PassBackend::Raster;
  }
  if (decided) {
    std::ostringstream why;
    why.precision(3);
    why << "auto: " << names_[slot(*decided)] << " faster (" << raster << " " << choice_.raster_ms << " ms, "
        << compute << " " << choice_.compute_ms << " ms, best of " << samples[0].size() << " and "
        << samples[1].size() << " frames)";
    return use(*decided, why.str());
  }
  const PassBackend next = samples[0].size() <= samples[1].size() ? PassBackend::Raster : PassBackend::Compute;
  pending = PendingFrame{next, frame_index};
  probing_ = true;
  return use(next, "probing");
}

}  // namespace shadows::detail
