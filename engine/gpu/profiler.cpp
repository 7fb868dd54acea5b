#include "engine/gpu/profiler.hpp"

#include <algorithm>

namespace engine::gpu {

GpuProfiler::GpuProfiler(const Context& ctx, uint32_t max_regions, size_t history_frames)
    : ctx_(ctx), capacity_(max_regions * 2), history_frames_(std::max<size_t>(history_frames, 1)) {
  if (!ctx.features().timestamps) return;  // profiler stays disabled; times read as 0
  VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  info.queryType = VK_QUERY_TYPE_TIMESTAMP;
  info.queryCount = capacity_;
  VK_CHECK(vkCreateQueryPool(ctx.device(), &info, ctx.allocator(), &pool_));
  ctx.set_name(pool_, VK_OBJECT_TYPE_QUERY_POOL, "gpu profiler timestamps");
}

GpuProfiler::~GpuProfiler() {
  if (pool_) vkDestroyQueryPool(ctx_.device(), pool_, ctx_.allocator());
}

void GpuProfiler::begin_frame(VkCommandBuffer cmd) {
  used_ = 0;
  regions_.clear();
  if (pool_) vkCmdResetQueryPool(cmd, pool_, 0, capacity_);
}

void GpuProfiler::begin(VkCommandBuffer cmd, const std::string& name) {
  if (!pool_ || used_ + 2 > capacity_) return;
  regions_.push_back({name, used_++});
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_, regions_.back().begin_query);
  if (std::find(order_.begin(), order_.end(), name) == order_.end()) order_.push_back(name);
}

void GpuProfiler::end(VkCommandBuffer cmd, const std::string& name) {
  if (!pool_) return;
  for (auto it = regions_.rbegin(); it != regions_.rend(); ++it) {
    if (it->name == name && it->end_query == UINT32_MAX) {
      it->end_query = used_++;
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_, it->end_query);
      return;
    }
  }
}

void GpuProfiler::collect() {
  last_frame_.clear();
  if (!pool_ || used_ == 0) return;
  std::vector<uint64_t> stamps(used_);
  VK_CHECK(vkGetQueryPoolResults(ctx_.device(), pool_, 0, used_, stamps.size() * sizeof(uint64_t), stamps.data(),
                                 sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const double ns = ctx_.features().timestamp_period_ns;
  std::map<std::string, double> frame;
  for (const auto& r : regions_) {
    if (r.end_query == UINT32_MAX) continue;
    const double ms = double(stamps[r.end_query] - stamps[r.begin_query]) * ns * 1e-6;
    frame[r.name] += ms;  // a region recorded twice in a frame sums
  }
  // A known region that did not run this frame counts 0 ms, so histories stay aligned by frame.
  for (const auto& name : order_) {
    auto it = frame.find(name);
    const double ms = it == frame.end() ? 0.0 : it->second;
    if (it != frame.end()) last_frame_.emplace_back(name, ms);
    auto& h = history_[name];
    h.push_back(ms);
    if (h.size() > history_frames_) h.pop_front();
  }
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
