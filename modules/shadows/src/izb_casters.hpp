#pragma once
#include <cstdint>
#include <vector>

#include "gpu/resources.hpp"
#include "frame.hpp"
#include "izb_pipelines.hpp"
#include "shared/izb.h"

namespace shadows::detail {

// The world-space caster triangles, in draw order (the raster trace finds a fragment's triangle as
// its draw's first triangle plus the primitive index), written on the GPU from the module's geometry
// and a table of the caster draws (izb_casters.comp); each triangle also knows its caster draw, for the
// per-frame CSM choice, and what its alpha test needs. Rebuilt only when the table changed (casters
// moved, came, went or changed material) or a caster is deformed (Instance::deformed: new positions
// every frame): moving casters cost a small table upload and one dispatch.
// Buffers only grow. Also finds each caster draw's first triangle (for the raster trace's push constants).
class IzbCasters {
 public:
  explicit IzbCasters(engine::gpu::Context& ctx) : ctx_(ctx) {}
  void update(const Frame& frame, IzbPipelineCache& pipelines);
  // A point light's faces recorded together (IzbPass::record_faces) each write their own grid-space
  // triangles and their own section of the caster draws' words (frustum draws and listed triangles,
  // IzbParams::face_sections): up to kSections of them, one per face.
  static constexpr uint32_t kSections = 6;
  // Room for `sections` faces' grid-space triangles (one's at least), each grid_triangle_stride() apart.
  void ensure_grid_sections(uint32_t sections);
  VkDeviceSize grid_triangle_stride() const { return grid_triangle_stride_; }
  // Where section `section`'s words start, after the first's (IzbParams::face_sections.x).
  uint32_t face_section_words(uint32_t section) const { return section * (2 * caster_draws + triangle_count); }

  engine::gpu::Buffer triangles, grid_triangles, caster_draw_words;
  std::vector<uint32_t> first_triangle;  // per frame draw: its first caster triangle (casters only)
  std::vector<uint32_t> caster_items;    // per caster draw, in order: its index in the frame's draws
  uint32_t triangle_count = 0;
  uint32_t caster_draws = 0;

 private:
  void list_caster_draws(const Frame& frame);
  void ensure_draw_words();
  bool table_unchanged(uint64_t frame_index) const;
  void ensure_triangle_buffers();
  void upload_draw_bounds(const Frame& frame);
  const engine::gpu::Buffer& upload_table(const Frame& frame);
  void record_triangle_build(const Frame& frame, const engine::gpu::Buffer& table, const engine::gpu::Pipeline& build);
  // Where the caster triangles are read: the compute passes and the raster trace's fragment and (where
  // the device has them) geometry shaders.
  VkPipelineStageFlags2 triangle_readers() const;

  engine::gpu::Context& ctx_;
  size_t triangle_capacity_ = 0;
  uint32_t grid_sections_ = 1;
  VkDeviceSize grid_triangle_stride_ = 0;
  uint64_t caster_draw_word_capacity_ = 0;
  std::vector<gpu_shared::IzbCasterDraw> caster_table_;  // this frame's caster draws
  std::vector<gpu_shared::IzbCasterDraw> built_table_;   // the caster draws `triangles` was built from
  std::vector<engine::gpu::Buffer> caster_tables_;       // per frame-in-flight slot: the table the build read
  bool draws_deformed_ = false;  // this frame's table holds a deformed slot: rebuilt every frame
  uint64_t built_frame_ = ~uint64_t(0);  // the frame `triangles` was last built in
};

}  // namespace shadows::detail
