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
                               const engine::gpu::GpuProfiler& profiler, uint32_t frame_slot) {
  if (key != key_ || !probe_) {
    key_ = key;
    if (probes_.size() >= kRememberedKeys && !probes_.count(key)) probes_.clear();
    probe_ = &probes_[key];
    pending_.clear();  // timed under the previous configuration
  }
  if (pending_.size() <= frame_slot) pending_.resize(frame_slot + 1);
  std::optional<PassBackend>& pending = pending_[frame_slot];
  auto& samples = probe_->samples;
  auto& decided = probe_->decided;
  if (pending) {
    // Only whole frames count: the region of the frame that last used this slot (collected in the
    // profiler's segment of the same index: the host's frame N uses slot and segment N % F), if this
    // pass recorded it.
    double total = 0.0;
    bool seen = false;
    for (const auto& [name, ms] : profiler.last_frame_of_slot(frame_slot))
      if (std::find(regions_.begin(), regions_.end(), name) != regions_.end()) {
        total += ms;
        seen = true;
      }
    if (seen) samples[slot(*pending)].push_back(total);
    pending.reset();
  }
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
  pending = next;
  probing_ = true;
  return use(next, "probing");
}

}  // namespace shadows::detail
