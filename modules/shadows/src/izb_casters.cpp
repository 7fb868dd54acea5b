#include "barriers.hpp"
#include "izb_casters.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

VkPipelineStageFlags2 IzbCasters::triangle_readers() const {
  return VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT |
         (ctx_.features().geometry_shader ? VK_PIPELINE_STAGE_2_GEOMETRY_SHADER_BIT : 0);
}

void IzbCasters::update(const Frame& frame, IzbPipelineCache& pipelines) {
  list_caster_draws(frame);
  ensure_draw_words();
  if (table_unchanged(frame.view.frame_index)) return;
  ensure_triangle_buffers();
  built_table_ = caster_table_;
  built_frame_ = frame.view.frame_index;
  if (triangle_count == 0) return;
  upload_draw_bounds(frame);
  const Buffer& table = upload_table(frame);
  record_triangle_build(frame, table, pipelines.build_casters());
}

void IzbCasters::list_caster_draws(const Frame& frame) {
  first_triangle.assign(frame.draws.size(), 0);
  caster_table_.clear();
  caster_items.clear();
  draws_deformed_ = false;
  uint32_t caster_triangles = 0;
  for (size_t i = 0; i < frame.draws.size(); ++i) {
    const DrawItem& d = frame.draws[i];
    if (!d.shadow.casts_shadow) continue;
    const MeshRange& range = frame.geometry.mesh(d.mesh);
    draws_deformed_ = draws_deformed_ || range.deformed;
    gpu_shared::IzbCasterDraw c{};
    c.world = d.world;
    c.first_index = range.first_index;
    c.vertex_offset = range.vertex_offset;
    c.triangle_count = range.index_count / 3;
    c.first_triangle = caster_triangles;
    c.ordinal = uint32_t(caster_table_.size());
    c.alpha_threshold = d.alpha_threshold;
    c.texture = d.base_color_texture;
    caster_table_.push_back(c);
    first_triangle[i] = caster_triangles;
    caster_items.push_back(uint32_t(i));
    caster_triangles += c.triangle_count;
  }
  caster_draws = uint32_t(caster_table_.size());
  triangle_count = caster_triangles;
}

void IzbCasters::ensure_draw_words() {
  // Flags, bounds and the frustum's draws per caster draw, then the listed triangles (izb.h); then
  // the other faces' frustum draws and listed triangles.
  const uint64_t words = 11 * uint64_t(caster_table_.size()) + triangle_count +
                         uint64_t(kSections - 1) * (2 * uint64_t(caster_table_.size()) + triangle_count);
  if (words > caster_draw_word_capacity_ || !caster_draw_words.valid()) {
    caster_draw_word_capacity_ = std::max<uint64_t>(words, 1);
    caster_draw_words = Buffer(ctx_, caster_draw_word_capacity_ * sizeof(uint32_t),
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false,
                               "izb caster draws");
    built_table_.clear();  // a new buffer holds no bounds yet
  }
}

bool IzbCasters::table_unchanged(uint64_t frame_index) const {
  // Mesh ranges are never reused (the geometry only grows), so an equal table means equal triangles,
  // except over a deformed slot, whose positions (and bounds) are the frame's own: built once a frame.
  if (draws_deformed_ && built_frame_ != frame_index) return false;
  const size_t table_bytes = caster_table_.size() * sizeof(gpu_shared::IzbCasterDraw);
  // (A frame without casters has empty tables, whose data() may be null: memcmp must not see them.)
  return triangles.valid() && built_table_.size() == caster_table_.size() &&
         (table_bytes == 0 || std::memcmp(built_table_.data(), caster_table_.data(), table_bytes) == 0);
}

void IzbCasters::ensure_triangle_buffers() {
  if (triangle_count > triangle_capacity_ || !triangles.valid()) {
    triangle_capacity_ = std::max<size_t>(triangle_count, 1);
    triangles = Buffer(ctx_, triangle_capacity_ * sizeof(gpu_shared::IzbCasterTriangle),
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "izb caster triangles");
    ensure_grid_sections(grid_sections_);
  }
}

void IzbCasters::ensure_grid_sections(uint32_t sections) {
  // 3 vec4 per triangle, then (spot lights) a list of the triangles traced apart; a section starts
  // where a storage buffer binding may.
  const VkDeviceSize stride =
      align_up(std::max<size_t>(triangle_capacity_, 1) * 4 * sizeof(glm::vec4),
               std::max<VkDeviceSize>(ctx_.properties().limits.minStorageBufferOffsetAlignment, 16));
  if (grid_triangles.valid() && stride == grid_triangle_stride_ && sections <= grid_sections_) return;
  grid_sections_ = std::max(grid_sections_, sections);
  grid_triangle_stride_ = stride;
  grid_triangles = Buffer(ctx_, stride * grid_sections_, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false,
                          "izb grid-space caster triangles");
}

// The light-frustum cull's bounds, in the command stream (earlier frames' passes still read the old
// ones; record_update orders them).
void IzbCasters::upload_draw_bounds(const Frame& frame) {
  std::vector<gpu_shared::IzbDrawBounds> bounds;
  bounds.reserve(caster_table_.size());
  for (size_t k = 0; k < caster_table_.size(); ++k) {
    const DrawItem& d = frame.draws[caster_items[k]];
    const gpu_shared::IzbCasterDraw& c = caster_table_[k];
    gpu_shared::IzbDrawBounds b{};
    const bool bounded = d.bounds.valid() && std::isfinite(d.bounds.min.x + d.bounds.min.y + d.bounds.min.z) &&
                         std::isfinite(d.bounds.max.x + d.bounds.max.y + d.bounds.max.z);
    b.lo = glm::vec4(bounded ? d.bounds.min : glm::vec3(1.0f), 0.0f);
    b.hi = glm::vec4(bounded ? d.bounds.max : glm::vec3(-1.0f), 0.0f);  // lo > hi: never culled
    std::memcpy(&b.lo.w, &c.first_triangle, 4);
    std::memcpy(&b.hi.w, &c.triangle_count, 4);
    bounds.push_back(b);
  }
  record_update(ctx_, frame.cmd, caster_draw_words, bounds.data(), bounds.size() * sizeof(bounds[0]),
                caster_table_.size() * sizeof(uint32_t));
}

// The table in this frame-in-flight slot's own host buffer: the frame that last read it (the slot's
// previous one) has completed, so it is rewritten and, when too small, replaced freely.
const Buffer& IzbCasters::upload_table(const Frame& frame) {
  const size_t table_bytes = caster_table_.size() * sizeof(gpu_shared::IzbCasterDraw);
  if (caster_tables_.size() <= frame.slot) caster_tables_.resize(frame.slot + 1);
  Buffer& table = caster_tables_[frame.slot];
  if (!table.valid() || table.size() < table_bytes)
    table = Buffer(ctx_, std::max<VkDeviceSize>(table_bytes, table.size() * 2), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                   true, "izb caster draw table");
  table.write(caster_table_.data(), table_bytes);  // made visible to the device by the submission
  return table;
}

void IzbCasters::record_triangle_build(const Frame& frame, const Buffer& table, const Pipeline& build) {
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(ctx_, frame.profiler, cmd, "izb_casters");
  // Earlier frames' reads of the triangles (compute passes, the raster trace's geometry and fragment
  // shaders) finish before they are overwritten.
  memory_barrier(cmd, triangle_readers(), 0, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0);
  build.bind(cmd);
  DescriptorWriter()
      .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_VERTICES, frame.geometry.vertices().handle())
      .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_INDICES, frame.geometry.indices().handle())
      .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_DRAWS, table.handle())
      .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_TRIANGLES, triangles.handle())
      .push(ctx_, cmd, build);
  const uint32_t groups = (triangle_count + 63) / 64;
  const uint32_t groups_x = std::min(groups, ctx_.properties().limits.maxComputeWorkGroupCount[0]);
  const gpu_shared::IzbCastersPush push{caster_draws, triangle_count, groups_x, 0u};
  build.push_constants(cmd, push);
  vkCmdDispatch(cmd, groups_x, (groups + groups_x - 1) / groups_x, 1);
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, triangle_readers(),
                 VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

}  // namespace shadows::detail
