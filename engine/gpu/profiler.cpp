#include "gpu/profiler.hpp"

#include <algorithm>

namespace engine::gpu {

GpuProfiler::GpuProfiler(const Context& ctx, uint32_t max_regions, size_t history_frames, uint32_t frames_in_flight)
    : ctx_(ctx),
      capacity_(max_regions * 2),
      frames_in_flight_(std::max(frames_in_flight, 1u)),
      history_frames_(std::max<size_t>(history_frames, 1)) {
  last_by_segment_.resize(frames_in_flight_);
  create_pool();
}

GpuProfiler::~GpuProfiler() {
  if (pool_) vkDestroyQueryPool(ctx_.device(), pool_, ctx_.allocator());
}

void GpuProfiler::create_pool() {
  if (pool_) vkDestroyQueryPool(ctx_.device(), pool_, ctx_.allocator());
  pool_ = VK_NULL_HANDLE;
  if (!ctx_.features().timestamps) return;  // profiler stays disabled; times read as 0
  VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  info.queryType = VK_QUERY_TYPE_TIMESTAMP;
  info.queryCount = capacity_ * frames_in_flight_;
  VK_CHECK(vkCreateQueryPool(ctx_.device(), &info, ctx_.allocator(), &pool_));
  ctx_.set_name(pool_, VK_OBJECT_TYPE_QUERY_POOL, "gpu profiler timestamps");
}

void GpuProfiler::set_frames_in_flight(uint32_t frames) {
  frames = std::max(frames, 1u);
  frames_.clear();
  next_segment_ = 0;
  last_by_segment_.assign(frames, {});
  if (frames == frames_in_flight_) return;
  frames_in_flight_ = frames;
  create_pool();
}

void GpuProfiler::begin_frame(VkCommandBuffer cmd) {
  // The host never collected the oldest frame (it did not wait for it): its segment is reused.
  if (frames_.size() >= frames_in_flight_) frames_.pop_front();
  Frame f;
  f.first_query = uint32_t(next_segment_++ % frames_in_flight_) * capacity_;
  frames_.push_back(std::move(f));
  // The segment's previous frame completed before this one is recorded (the host's promise), and its
  // results were read by collect() or dropped above.
  if (pool_) vkCmdResetQueryPool(cmd, pool_, frames_.back().first_query, capacity_);
}

void GpuProfiler::cancel_frame() {
  if (!frames_.empty()) frames_.pop_back();
}

void GpuProfiler::begin(VkCommandBuffer cmd, const std::string& name) {
  if (!pool_ || frames_.empty()) return;
  Frame& f = frames_.back();
  // Room for this region's two queries and the end query of every region still open around it: a
  // region past the pool is left untimed, never written outside its segment.
  const auto open = std::count_if(f.regions.begin(), f.regions.end(), [](const Open& r) { return r.end_query == UINT32_MAX; });
  if (f.used + 2 + uint32_t(open) > capacity_) return;
  if (std::find(order_.begin(), order_.end(), name) == order_.end()) {
    order_.push_back(name);
    const auto innermost = std::find_if(f.regions.rbegin(), f.regions.rend(), [](const Open& r) { return r.end_query == UINT32_MAX; });
    parent_[name] = innermost == f.regions.rend() ? std::string() : innermost->name;
  }
  f.regions.push_back({name, f.first_query + f.used++});
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_, f.regions.back().begin_query);
}

void GpuProfiler::end(VkCommandBuffer cmd, const std::string& name) {
  if (!pool_ || frames_.empty()) return;
  Frame& f = frames_.back();
  for (auto it = f.regions.rbegin(); it != f.regions.rend(); ++it) {
    if (it->name == name && it->end_query == UINT32_MAX) {
      it->end_query = f.first_query + f.used++;
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_, it->end_query);
      return;
    }
  }
}

void GpuProfiler::collect() {
  last_frame_.clear();
  if (frames_.empty()) return;
  const Frame f = std::move(frames_.front());
  frames_.pop_front();
  auto& by_segment = last_by_segment_[capacity_ ? f.first_query / capacity_ : 0];
  by_segment.clear();
  if (!pool_ || f.used == 0) return;
  std::vector<uint64_t> stamps(f.used);
  VK_CHECK(vkGetQueryPoolResults(ctx_.device(), pool_, f.first_query, f.used, stamps.size() * sizeof(uint64_t),
                                 stamps.data(), sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const double ns = ctx_.features().timestamp_period_ns;
  std::map<std::string, double> frame;
  for (const auto& r : f.regions) {
    if (r.end_query == UINT32_MAX) continue;
    const double ms = double(stamps[r.end_query - f.first_query] - stamps[r.begin_query - f.first_query]) * ns * 1e-6;
    frame[r.name] += ms;  // a region recorded twice in a frame sums
  }
  // A known region that did not run this frame counts 0 ms, so histories stay aligned by frame.
  for (const auto& name : order_) {
    auto it = frame.find(name);
    const double ms = it == frame.end() ? 0.0 : it->second;
    if (it != frame.end()) {
      last_frame_.emplace_back(name, ms);
      by_segment.emplace_back(name, ms);
    }
    auto& h = history_[name];
    h.push_back(ms);
    if (h.size() > history_frames_) h.pop_front();
  }
}

std::vector<std::string> GpuProfiler::children(const std::string& parent) const {
  std::vector<std::string> names;
  for (const auto& name : order_) {
    const auto it = parent_.find(name);
    if (it != parent_.end() && it->second == parent) names.push_back(name);
  }
  return names;
}

double GpuProfiler::average_ms(const std::string& name, size_t last_n) const {
  auto it = history_.find(name);
  if (it == history_.end() || it->second.empty()) return 0.0;
  const auto& v = it->second;
  const size_t n = last_n ? std::min(last_n, v.size()) : v.size();
  double sum = 0;
  for (size_t i = v.size() - n; i < v.size(); ++i) sum += v[i];
  return sum / double(n);
}

double GpuProfiler::median_ms(const std::string& name) const {
  auto it = history_.find(name);
  if (it == history_.end() || it->second.empty()) return 0.0;
  std::vector<double> v(it->second.begin(), it->second.end());
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<double> GpuProfiler::history(const std::string& name) const {
  auto it = history_.find(name);
  return it == history_.end() ? std::vector<double>{} : std::vector<double>(it->second.begin(), it->second.end());
}

void GpuProfiler::clear_history() {
  history_.clear();
}

}  // namespace engine::gpu
