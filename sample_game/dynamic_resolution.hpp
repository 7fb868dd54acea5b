#pragma once
#include <algorithm>
#include <vector>

namespace walkthrough {

// Holds a frame-time target by scaling the render size: every 8 frames the median frame time is
// compared with the target; over it shrinks each side by the square root of the ratio to 90% of the
// target (at most by half), clearly fast (under 70% of the target) grows it by 8%; the scale stays in
// [kMinScale, 1] in steps of 1/40. The first window holds the start's one-time work (pipelines made on
// first use, the shadow module's automatic choices timing both of their ways: on lavapipe three of
// its eight frames take 0.5-0.75 s, the rest 70-100 ms), so it changes nothing unless every frame is
// far over the target; a median of a start would otherwise shrink the picture for good, since it
// grows only when clearly fast.
class DynamicResolution {
 public:
  // 256x144 in a 1280x720 window: where a CPU device still misses the target, a blurrier picture
  // that keeps up beats a sharper one at half the rate.
  static constexpr float kMinScale = 0.2f;
  static constexpr float kAim = 0.9f;        // of the target, after a shrink
  static constexpr float kGrowBelow = 0.7f;  // of the target: grow only when this fast
  static constexpr float kSteps = 40.0f;     // scale steps per unit
  explicit DynamicResolution(float target_fps, float initial_scale = 1.0f)
      : target_ms_(1000.0f / target_fps), scale_(std::clamp(initial_scale, kMinScale, 1.0f)) {}
  // Feeds one frame's wall-clock time; returns true when scale() changed.
  bool add_frame(float ms);
  float scale() const { return scale_; }
  float target_ms() const { return target_ms_; }
  void set_target_fps(float fps) { target_ms_ = 1000.0f / std::max(fps, 1.0f); }
  float median_ms() const { return median_ms_; }
  bool enabled = true;

 private:
  float target_ms_;
  float scale_ = 1.0f;
  float median_ms_ = 0.0f;
  bool started_ = false;  // the first window is over
  std::vector<float> window_;
};

}  // namespace walkthrough
