#include "dynamic_resolution.hpp"

#include <cmath>

namespace walkthrough {

bool DynamicResolution::add_frame(float ms) {
  if (!enabled) {
    const bool changed = scale_ != 1.0f;
    scale_ = 1.0f;
    return changed;
  }
  window_.push_back(ms);
  if (window_.size() < 8) return false;
  std::vector<float> sorted = window_;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  median_ms_ = sorted[sorted.size() / 2];
  window_.clear();
  float next = scale_;
  if (median_ms_ > target_ms_ * 1.05f) {
    // Cost goes with the pixel count, so the side scales with the square root of the ratio.
    next = scale_ * std::max(0.7f, std::sqrt(target_ms_ / median_ms_));
  } else if (median_ms_ < target_ms_ * 0.75f) {
    next = scale_ * 1.08f;
  }
  next = std::clamp(std::round(next * 40.0f) / 40.0f, kMinScale, 1.0f);
  const bool changed = next != scale_;
  scale_ = next;
  return changed;
}

}  // namespace walkthrough
