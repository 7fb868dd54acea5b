#include "dynamic_resolution.hpp"

#include <algorithm>
#include <cmath>

namespace walkthrough {

bool DynamicResolution::add_frame(float ms) {
  if (!enabled) {
    const bool changed = scale_ != 1.0f;
    scale_ = 1.0f;
    return changed;
  }
  window_.push_back(ms);
  // Far over the target (every frame above 1.5x), act after half a window: a CPU device starting at
  // full size would otherwise spend its first seconds at a fraction of the target rate.
  const bool far_over = window_.size() >= 4 &&
                        std::all_of(window_.begin(), window_.end(), [&](float f) { return f > 1.5f * target_ms_; });
  if (window_.size() < 8 && !far_over) return false;
  std::vector<float> sorted = window_;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  median_ms_ = sorted[sorted.size() / 2];
  window_.clear();
  const bool start = !started_;
  started_ = true;
  if (start && !far_over) return false;  // the start's window (see the class comment)
  float next = scale_;
  if (median_ms_ > target_ms_) {
    // Cost goes with the pixel count, so the side scales with the square root of the ratio. It aims a
    // tenth under the target: aiming at the target itself would leave half the frames above it.
    next = std::floor(scale_ * std::max(0.5f, std::sqrt(kAim * target_ms_ / median_ms_)) * kSteps) / kSteps;
  } else if (median_ms_ < target_ms_ * kGrowBelow) {
    next = std::round(scale_ * 1.08f * kSteps) / kSteps;
  }
  next = std::clamp(next, kMinScale, 1.0f);
  const bool changed = next != scale_;
  scale_ = next;
  return changed;
}

}  // namespace walkthrough
