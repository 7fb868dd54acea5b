#pragma once
// GPU time per named pass from timestamp queries. Regions may nest; each frame's results are read
// after its fence, and history is kept so callers can ask for averages or medians over frames.
// With F frames in flight the query pool is split into F segments: begin_frame() takes the segment of
// the frame being recorded, collect() reads the oldest recorded frame's, so the history stays one
// sequence of frames in the order they ran.
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "gpu/context.hpp"

namespace engine::gpu {

class GpuProfiler {
 public:
  // The history keeps the last `history_frames` frames, so an application running for hours holds a
  // bounded amount (a benchmark's timed frames fit many times over).
  explicit GpuProfiler(const Context& ctx, uint32_t max_regions = 64, size_t history_frames = 4096,
                       uint32_t frames_in_flight = 1);
  ~GpuProfiler();
  GpuProfiler(const GpuProfiler&) = delete;
  GpuProfiler& operator=(const GpuProfiler&) = delete;

  bool enabled() const { return pool_ != VK_NULL_HANDLE; }
  uint32_t frames_in_flight() const { return frames_in_flight_; }
  // Resizes the pool for `frames` segments; frames recorded and not yet collected are dropped, so call
  // it while none is in flight.
  void set_frames_in_flight(uint32_t frames);
  // Starts a frame in the next segment. With frames_in_flight frames already recorded and not
  // collected, the oldest is dropped uncollected (its segment is reused).
  void begin_frame(VkCommandBuffer cmd);
  // Forgets the frame begun last: its commands will not be submitted (recording failed), so its
  // queries never complete and collect() must not wait for them.
  void cancel_frame();
  void begin(VkCommandBuffer cmd, const std::string& name);
  void end(VkCommandBuffer cmd, const std::string& name);
  // Call after the oldest recorded frame's commands completed; appends its times to the history.
  void collect();
  // Frames recorded (begin_frame) and not yet collected.
  size_t frames_pending() const { return frames_.size(); }

  // Milliseconds per region in the last collected frame, in first-seen order.
  const std::vector<std::pair<std::string, double>>& last_frame() const { return last_frame_; }
  // The same for the last collected frame that was recorded in segment `slot % frames_in_flight()`
  // (frame N records in segment N % F): what frame N + F reads back, even after several frames were
  // collected at once (a resize waits for all of them).
  const std::vector<std::pair<std::string, double>>& last_frame_of_slot(uint32_t slot) const {
    return last_by_segment_[slot % frames_in_flight_];
  }
  double average_ms(const std::string& name, size_t last_n = 0) const;
  double median_ms(const std::string& name) const;
  std::vector<std::string> region_names() const { return order_; }
  // The regions first recorded directly inside `parent` (no other region open between), in first-seen
  // order: what a region's time is made of, as far as regions name it.
  std::vector<std::string> children(const std::string& parent) const;
  // Per-frame times of one region since the last clear_history(), at most the last history_frames
  // (empty if never recorded).
  std::vector<double> history(const std::string& name) const;
  void clear_history();

 private:
  void create_pool();

  const Context& ctx_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t capacity_ = 0;  // queries per segment
  uint32_t frames_in_flight_ = 1;
  size_t history_frames_ = 0;
  uint64_t next_segment_ = 0;  // counts begin_frame calls
  struct Open {
    std::string name;
    uint32_t begin_query;  // absolute query index (segment base included)
    uint32_t end_query = UINT32_MAX;
  };
  // One recorded frame: its segment and regions, until collect() reads it.
  struct Frame {
    uint32_t first_query = 0;
    uint32_t used = 0;
    std::vector<Open> regions;
  };
  std::deque<Frame> frames_;  // oldest first; back() is the frame being recorded
  std::vector<std::string> order_;
  std::map<std::string, std::string> parent_;  // the innermost region open when a name was first recorded
  std::map<std::string, std::deque<double>> history_;
  std::vector<std::pair<std::string, double>> last_frame_;
  std::vector<std::vector<std::pair<std::string, double>>> last_by_segment_;
};

class ScopedGpuRegion {
 public:
  ScopedGpuRegion(const Context& ctx, GpuProfiler& profiler, VkCommandBuffer cmd, const std::string& name)
      : ctx_(ctx), profiler_(profiler), cmd_(cmd), name_(name) {
    ctx_.begin_label(cmd_, name_.c_str());
    profiler_.begin(cmd_, name_);
  }
  ~ScopedGpuRegion() {
    profiler_.end(cmd_, name_);
    ctx_.end_label(cmd_);
  }
  ScopedGpuRegion(const ScopedGpuRegion&) = delete;
  ScopedGpuRegion& operator=(const ScopedGpuRegion&) = delete;

 private:
  const Context& ctx_;
  GpuProfiler& profiler_;
  VkCommandBuffer cmd_;
  std::string name_;
};

// A ScopedGpuRegion only when `enabled` (detail a caller opts into: each region's timestamps wait for
// the work recorded before them).
class OptionalGpuRegion {
 public:
  OptionalGpuRegion(bool enabled, const Context& ctx, GpuProfiler& profiler, VkCommandBuffer cmd,
                    const std::string& name) {
    if (enabled) region_.emplace(ctx, profiler, cmd, name);
  }

 private:
  std::optional<ScopedGpuRegion> region_;
};

}  // namespace engine::gpu
