#include "barriers.hpp"
#include "izb_resources.hpp"

#include <algorithm>

#include "izb_frustum.hpp"
#include "shared/izb.h"

namespace shadows::detail {

using namespace engine::gpu;

IzbResources::IzbResources(Context& c) : ctx(c) {
  const VkPhysicalDeviceLimits& limits = c.properties().limits;
  storage_alignment = std::max<VkDeviceSize>(
      {limits.minStorageBufferOffsetAlignment, limits.minUniformBufferOffsetAlignment, 16});
  params_stride = aligned(sizeof(gpu_shared::IzbParams));
  params = Buffer(c, params_stride * kCounterSlices,
                  VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, "izb params");
  make_frame_data(0);
  counter_stride = align_up(counter_bytes(), std::max<VkDeviceSize>(limits.minStorageBufferOffsetAlignment, 4));
  counters = Buffer(c, counter_stride * kCounterSlices,
                    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                        VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                    false, "izb counters");
  nearest = Sampler(c, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "izb nearest");
}

void IzbResources::make_frame_data(VkDeviceSize fit_groups) {
  frame_stride = aligned((gpu_shared::kIzbPartialsAt + fit_groups) * 16);
  frame_data = Buffer(ctx, frame_stride * kCounterSlices,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
                          VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                      false, "izb frame and fit bounds per workgroup");
}

void IzbResources::ensure_buffers(const Frame& frame, const IzbSettings& s, uint32_t grid_resolution) {
  const uint32_t spp = izb_sample_count(s);
  if (allocated_resolution != s.resolution) allocate_grid(frame.cmd, s.resolution);
  use_grid(grid_resolution);
  const VkExtent2D e = frame.view.extent;
  if (e.width != extent.width || e.height != extent.height || spp != samples) ensure_view(e, spp);
  ensure_node_pool(s, VkDeviceSize(e.width) * e.height, spp);
}

VkDeviceSize IzbResources::csm_texel_bytes() const {
  const VkDeviceSize tile_words = 8 * VkDeviceSize(tiles_per_side) * tiles_per_side;
  return (gpu_shared::izb_lit_tile_records_at(resolution) + tile_words) * 4;
}

void IzbResources::use_grid(uint32_t grid_resolution) {
  resolution = grid_resolution;
  const VkDeviceSize texels = VkDeviceSize(resolution) * resolution;
  scan_blocks = uint32_t((texels + gpu_shared::kIzbScanBlock - 1) / gpu_shared::kIzbScanBlock);
  tiles_per_side = (resolution + gpu_shared::kIzbTile - 1) / gpu_shared::kIzbTile;
}

// Per texel of the grid: list heads or counts, farthest node depths, the compute CSM and lit map.
// Every size grows with the resolution, so a smaller grid fits in these buffers.
void IzbResources::allocate_grid(VkCommandBuffer cmd, uint32_t grid_resolution) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  use_grid(grid_resolution);
  allocated_resolution = grid_resolution;
  const VkDeviceSize texels = VkDeviceSize(resolution) * resolution;
  heads = Buffer(ctx, texels * 4, usage, false, "izb heads");
  list_counts = Buffer(ctx, texels * 4, usage, false, "izb sorted list counts");
  list_cursor = Buffer(ctx, (texels + scan_blocks) * 4, usage, false, "izb sorted list fill cursors and block sums");
  // The compute CSM's depths, then the lit map's texels, texel corners and tile records (izb.h;
  // one binding for all).
  const VkDeviceSize lit_words = csm_texel_bytes() / 4;
  csm_texels = Buffer(ctx, lit_words * 4,
                      usage | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT, false,
                      "csm compute depths and lit map");
  csm_texels.make_texel_view(VK_FORMAT_R32_UINT,
                             std::min<VkDeviceSize>(lit_words, ctx.properties().limits.maxTexelBufferElements), 4);
  // Per texel, then per tile (tile_farthest_index): the farthest node depth.
  farthest = Buffer(ctx, (texels + VkDeviceSize(tiles_per_side) * tiles_per_side) * 4,
                    usage | VK_BUFFER_USAGE_TRANSFER_SRC_BIT, false, "izb farthest node depth per texel and tile");
  trace_depth = Image(ctx, {resolution, resolution}, VK_FORMAT_D32_SFLOAT,
                      VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                      "izb trace depth (farthest node)");
  to_general(ctx, cmd, trace_depth);
}

// Per pixel of the view: the visibility mask, its state, overflow list, occluder distance and
// light-space data, and the fit's per-workgroup bounds.
void IzbResources::ensure_view(VkExtent2D e, uint32_t spp) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  const VkDeviceSize pixels = VkDeviceSize(e.width) * e.height;
  extent = e;
  samples = spp;
  mask = Buffer(ctx, pixels * 4, usage, false, "izb visibility mask");
  pixel_state = Buffer(ctx, pixels * 4, usage, false, "izb pixel state");
  overflow_list = Buffer(ctx, pixels * 4, usage, false, "izb overflow pixels");
  occluder_distance = Buffer(ctx, pixels * 4, usage, false, "izb nearest occluder distance");
  make_frame_data(VkDeviceSize(fit_columns(e.width)) * fit_rows(e.height));
  const uint32_t stride = spp == 32 ? gpu_shared::kIzbQuadFloats32 : gpu_shared::kIzbQuadFloats1;
  quads = Buffer(ctx, pixels * stride * 4, usage, false, "izb pixel light-space data");
  pool_size = 0;
}

void IzbResources::ensure_node_pool(const IzbSettings& s, VkDeviceSize pixels, uint32_t spp) {
  uint64_t wanted;
  if (s.brute_force) {
    wanted = 0;
  } else if (s.node_pool_override) {
    wanted = s.node_pool_override;
  } else {
    // 1 spp needs at most one node per pixel. At 32 spp a μQuad spans about (texels per pixel)
    // texels, at least one; the pool then grows to the measured demand if a frame overflows.
    const double texels_per_pixel = double(s.resolution) * s.resolution / double(pixels);
    const double per_pixel = spp == 32 ? std::max(2.0, 2.0 * texels_per_pixel) : 1.0;
    wanted = std::max<uint64_t>(uint64_t(double(pixels) * per_pixel * s.node_pool_factor), 1024);
    wanted = std::max(wanted, pool_demand);
    // Never beyond one storage buffer's range: insertions past it take the exact overflow fallback.
    wanted = std::min<uint64_t>(wanted, ctx.properties().limits.maxStorageBufferRange / 8);
  }
  if (wanted != pool_size || !nodes.valid()) {
    pool_size = wanted;
    nodes = Buffer(ctx, std::max<uint64_t>(pool_size, 1) * 8,
                   VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, "izb nodes");
  }
}

void IzbResources::allocate_work_list(IzbWorkList& list, uint64_t capacity, uint32_t slices, VkDeviceSize entry_bytes,
                                      const char* name) {
  list.capacity = capacity;
  list.slices = slices;
  list.stride = aligned(capacity * entry_bytes);
  list.buffer = Buffer(ctx, list.stride * slices, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, name);
}

void IzbResources::ensure_work_lists(bool used, uint32_t triangle_count) {
  auto ensure = [&](IzbWorkList& list, uint64_t initial, VkDeviceSize stride, const char* name) {
    const uint64_t want = used ? std::max(initial, list.demand) : 1;
    if (list.buffer.valid() && want <= list.capacity) return;
    allocate_work_list(list, want, list.slices, stride, name);
  };
  const uint64_t tiles = uint64_t(tiles_per_side) * tiles_per_side;
  ensure(records, std::max<uint64_t>(uint64_t(triangle_count) * 2, 16384), 16, "izb tile-row records");
  ensure(tile_pairs, std::max<uint64_t>({uint64_t(triangle_count) * 4, tiles * 4, 65536}), 8, "izb tile pairs");
  ensure(pairs, std::max<uint64_t>({uint64_t(triangle_count) * 4, uint64_t(resolution) * resolution / 2, 65536}), 8,
         "izb texel pairs");
}

void IzbResources::ensure_grid_slices(uint32_t slices) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  // (Below a whole grid's size, allocate_grid's buffers serve; they only grow.)
  if (heads.size() < heads_stride() * slices)
    heads = Buffer(ctx, heads_stride() * slices, usage, false, "izb heads");
  if (farthest.size() < farthest_stride() * slices)
    farthest = Buffer(ctx, farthest_stride() * slices, usage | VK_BUFFER_USAGE_TRANSFER_SRC_BIT, false,
                      "izb farthest node depth per texel and tile");
  auto ensure = [&](IzbWorkList& list, VkDeviceSize entry_bytes, const char* name) {
    if (list.slices < slices) allocate_work_list(list, list.capacity, slices, entry_bytes, name);
  };
  ensure(records, 16, "izb tile-row records");
  ensure(tile_pairs, 8, "izb tile pairs");
  ensure(pairs, 8, "izb texel pairs");
}

void IzbResources::ensure_resolve_list(VkExtent2D e, bool listed, bool face_tiles) {
  VkDeviceSize want = listed ? VkDeviceSize(e.width) * e.height * 4 : 4;
  if (face_tiles) want = std::max<VkDeviceSize>(want, VkDeviceSize(gpu_shared::light_tile_words(e.width, e.height)) * 4);
  if (resolve_list.valid() && resolve_list.size() >= want) return;
  resolve_list = Buffer(ctx, want,
                        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                            VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                        false, "izb resolve pixel list");
}

}  // namespace shadows::detail
