#pragma once
#include <algorithm>
#include <cstdint>

#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"
#include "shared/izb.h"

namespace shadows::detail {

// A compute trace / CSM work list (see izb.h), grown to the demand a frame measured.
// A point light's faces recorded together each take a slice of `capacity` entries.
struct IzbWorkList {
  engine::gpu::Buffer buffer;
  uint64_t capacity = 0, demand = 0;
  uint32_t slices = 1;
  VkDeviceSize stride = 0;  // bytes per slice
};

// The IZB's buffers and images: per grid (lists, farthest depths, lit map), per view (pixels' nodes
// and light-space data), the node pool and the work lists. Every pass binds all of them (izb_bindings()).
// The samples a pixel the IZB takes for `s`: 32 where asked, else 1.
inline uint32_t izb_sample_count(const IzbSettings& s) { return s.samples_per_pixel == 32 ? 32u : 1u; }

struct IzbResources {
  explicit IzbResources(engine::gpu::Context& c);

  // Sizes everything for this record's grid (`grid_resolution` texels a side, at most s.resolution),
  // view and sample count, and the node pool for `s`. The grid's buffers hold s.resolution: a smaller
  // grid (a point light's face) uses their first texels, not buffers of its own.
  void ensure_buffers(const Frame& frame, const IzbSettings& s, uint32_t grid_resolution);
  // The bytes of a word per texel of this grid (its lists' heads or counts, the compute CSM's depths)
  // and of its farthest depths (texels, then tiles).
  VkDeviceSize texel_word_bytes() const { return VkDeviceSize(resolution) * resolution * 4; }
  VkDeviceSize farthest_bytes() const {
    return (VkDeviceSize(resolution) * resolution + VkDeviceSize(tiles_per_side) * tiles_per_side) * 4;
  }
  // The bytes of csm_texels this grid uses: the compute CSM's depths, then the lit map's words.
  VkDeviceSize csm_texel_bytes() const;
  // The compute passes' work lists: first sized from the scene and grid, then grown to the demand a
  // frame measured (a frame that overflows still finishes exactly, only slower). Unused (raster
  // passes only): small placeholders keep every binding valid.
  void ensure_work_lists(bool used, uint32_t triangle_count);
  // Frame-sized where the resolve is listed, a point light's face tile lists where its faces build
  // over them (IZB_FLAG_FACE_TILES); otherwise a placeholder keeps the binding valid.
  void ensure_resolve_list(VkExtent2D e, bool listed, bool face_tiles);
  // Hybrid: the list frame-sized (its pixels only with a limited range, which the soft term needs
  // too); otherwise 1x1 placeholders keep the bindings valid (izb_hybrid.cpp).
  void ensure_hybrid(VkCommandBuffer cmd, VkExtent2D e, bool hybrid, bool limited_range);
  // A point light's faces recorded together (IzbPass::record_faces): each face's grid (list heads,
  // farthest depths), parameters, fit frame and work lists in a slice of their own; `grid_slice` is the
  // one this record's passes bind (0 for any other record). Grows the grid's and the work lists'
  // buffers to `slices` slices of this record's sizes; after ensure_buffers and ensure_work_lists.
  void ensure_grid_slices(uint32_t slices);
  uint32_t grid_slice = 0;
  // Bytes between slices, and where this record's starts.
  VkDeviceSize params_stride = 0, frame_stride = 0;
  VkDeviceSize heads_stride() const { return aligned(texel_word_bytes()); }
  VkDeviceSize farthest_stride() const { return aligned(farthest_bytes()); }
  VkDeviceSize slice_at(VkDeviceSize stride) const { return stride * grid_slice; }
  // This record's slice of `buffer` (a whole grid's buffer may end short of its last stride).
  VkDeviceSize slice_range(const engine::gpu::Buffer& buffer, VkDeviceSize stride) const {
    return std::min(stride, buffer.size() - slice_at(stride));
  }
  // Whether csm_texels' texel view reaches all of its words (IZB_FLAG_LIT_FETCH).
  bool lit_view_whole() const { return csm_texel_bytes() / 4 <= ctx.properties().limits.maxTexelBufferElements; }

  engine::gpu::Context& ctx;
  engine::gpu::Buffer list_counts, list_cursor;  // the cursors' buffer also holds the prefix sum's block sums
  uint32_t scan_blocks = 0;
  // IZB_FLAG_LISTED_RESOLVE: the pixels with nodes; IZB_FLAG_FACE_TILES: the faces' tile lists and
  // their builds' indirect dispatches (light_tiles.h).
  engine::gpu::Buffer resolve_list;
  // Hybrid: the cascades' term and the pixels that blend toward it (frame-sized only in hybrid with a
  // limited range), and the penumbra pass's tiles.
  engine::gpu::Image soft_term;
  engine::gpu::Buffer hybrid_list;
  VkExtent2D hybrid_extent{};
  bool hybrid_limited = false;  // the hybrid's range is limited: the list's pixels and the soft term
  engine::gpu::Image trace_depth;
  engine::gpu::Buffer params;
  // The counters: a record's in a slice of its own, at `counter_stride` bytes per slice, so that a
  // point light's faces are read back with one copy after the last (a face's record takes the slice
  // of its place among the faces recorded, View::light_face_order; any other record the first).
  static constexpr uint32_t kCounterSlices = 6;
  engine::gpu::Buffer counters;
  VkDeviceSize counter_stride = 0;
  uint32_t counter_slice = 0;
  static constexpr VkDeviceSize counter_bytes() { return gpu_shared::IZB_COUNTER_COUNT * sizeof(uint32_t); }
  VkDeviceSize counter_slice_offset() const { return counter_stride * counter_slice; }
  // The byte offset of this record's counter word `counter` in `counters`.
  VkDeviceSize counter_at(uint32_t counter) const { return counter_slice_offset() + VkDeviceSize(counter) * 4; }
  // The frame the fit writes (IzbFrame), then its per-workgroup bounds from vec4 kIzbPartialsAt on
  // (izb.h): storage for the fit, a uniform buffer's range for the passes after it; a slice per face.
  engine::gpu::Buffer frame_data;
  ReadbackRing counters_readback;
  engine::gpu::Buffer heads, farthest, nodes, mask, pixel_state, quads, overflow_list, occluder_distance;
  engine::gpu::Buffer csm_texels;
  IzbWorkList records, tile_pairs, pairs;
  uint32_t tiles_per_side = 0;
  engine::gpu::Sampler nearest;
  uint32_t resolution = 0;           // this record's grid, texels a side
  uint32_t allocated_resolution = 0;  // the grid the buffers hold (IzbSettings::resolution, at least `resolution`)
  uint32_t samples = 0;
  VkExtent2D extent{};
  uint64_t pool_size = 0;
  uint64_t pool_demand = 0;

 private:
  VkDeviceSize aligned(VkDeviceSize bytes) const { return engine::gpu::align_up(bytes, storage_alignment); }
  void make_frame_data(VkDeviceSize fit_groups);
  void allocate_work_list(IzbWorkList& list, uint64_t capacity, uint32_t slices, VkDeviceSize entry_bytes,
                          const char* name);
  VkDeviceSize storage_alignment = 16;  // of a storage or uniform buffer binding's offset
  void allocate_grid(VkCommandBuffer cmd, uint32_t grid_resolution);
  void use_grid(uint32_t grid_resolution);  // resolution and what follows from it, in the buffers there are
  void ensure_view(VkExtent2D e, uint32_t spp);
  void ensure_node_pool(const IzbSettings& s, VkDeviceSize pixels, uint32_t spp);
};

}  // namespace shadows::detail
