#include "barriers.hpp"
#include "izb_lit_map.hpp"

#include "izb_batch.hpp"

#include <cstring>

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

void record_lit_map(IzbState& s, IzbBatch& batch, const IzbSettings& settings) {
  Frame& frame = batch.frame();
  // The barrier after it orders it with the compute CSM, which shares its work lists. The build reads it.
  VkCommandBuffer cmd = frame.cmd;
  const VkDeviceSize csm_depth_bytes = s.res.texel_word_bytes();  // the lit map's words follow them
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "lit_map");
  vkCmdFillBuffer(cmd, s.res.csm_texels.handle(), csm_depth_bytes, s.res.csm_texel_bytes() - csm_depth_bytes,
                  gpu_shared::kIzbLitEmpty);
  pass_barrier(frame.ctx, cmd);
  s.record_tile_work(cmd, batch, gpu_shared::IZB_WORK_LIT, "lit", settings.step_timings);
  pass_barrier(frame.ctx, cmd);
}

LitMapSnapshot read_lit_map(IzbState& s) {
  LitMapSnapshot snapshot;
  if (!s.last.lit) return snapshot;
  const uint32_t resolution = s.res.resolution;
  snapshot.resolution = resolution;
  const auto bytes = read_buffer(s.ctx, s.res.csm_texels);
  // Ordered bits -> floats (izb_common.glsl), `count` words from word `first` on.
  const auto decode = [&](size_t first, size_t count) {
    std::vector<float> depths(count);
    for (size_t i = 0; i < count; ++i) {
      uint32_t bits;
      std::memcpy(&bits, bytes.data() + (first + i) * 4, 4);
      bits = (bits & 0x80000000u) ? (bits & 0x7fffffffu) : ~bits;
      std::memcpy(&depths[i], &bits, 4);
    }
    return depths;
  };
  const size_t texels = size_t(resolution) * resolution;
  snapshot.depth = decode(texels, texels);
  const size_t corners = size_t(resolution + 1) * (resolution + 1);
  snapshot.corner_depth = decode(2 * texels, corners);
  snapshot.tile = gpu_shared::kIzbTile;
  snapshot.tiles_per_side = s.res.tiles_per_side;
  const size_t tiles = size_t(s.res.tiles_per_side) * s.res.tiles_per_side;
  // Each tile's record (izb_common.glsl, lit_tile_record): least texel bound, bound, c00, c10, c01, c11.
  const std::vector<float> records = decode(gpu_shared::izb_lit_tile_records_at(resolution), 8 * tiles);
  for (size_t t = 0; t < tiles; ++t) {
    snapshot.tile_least_depth.push_back(records[8 * t]);
    snapshot.tile_depth.push_back(records[8 * t + 1]);
    snapshot.tile_corner_depth.insert(snapshot.tile_corner_depth.end(), records.begin() + 8 * t + 2,
                                      records.begin() + 8 * t + 6);
  }
  snapshot.light_view_projection = s.read_light_view_projection();
  return snapshot;
}

}  // namespace shadows::detail
