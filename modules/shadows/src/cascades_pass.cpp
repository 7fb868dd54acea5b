// Cascaded filtered shadow maps. Per frame: fit the cascades (cascade_fit.cpp) -> cascade_depth (one
// D32 layer per cascade) -> cascade_masks (edge flag and depth extent per texel of each cascade's
// mask level over its receivers' rectangle, then combined over each texel's 2x2 neighbourhoods) ->
// cascade_filter (rotated 12-tap Poisson PCF or one tap, per pixel; for a sun with a size, PCSS in the
// pixel's cascade (pcss.glsl) wherever its penumbra is wider than the 12-tap kernel, the penumbra's
// radius taken in world units and converted with the cascade's own texel size, so it runs on
// unbroken across splits and blend bands; a classify stage over the frame
// takes the one tap where the mask allows and lists the pixels that need the kernel or lie in a
// blend band; two stages over those lists, with indirect dispatches, finish them; with masking off
// the classify stage takes the kernel itself and lists only the band) -> cascade_blur
// (5x5 on pixels whose taps disagreed, over a compacted list, into a side buffer that a second
// dispatch writes back).
//
// Why lists rather than branches: Mesa's llvmpipe (lavapipe) runs both sides of every branch for all
// lanes of its SIMD rows, so a per-pixel `if (needs kernel)` made every pixel pay for the 12 taps
// whatever the mask said. A pipeline per stage (specialization constants for stage, masking and debug
// view) leaves each stage only the code it runs. On a GPU the same split replaces divergent kernels
// in the full-screen pass with compact list dispatches.
//
// When skipping the kernel is exact. Every tap compares the receiver's tangent plane, evaluated at
// the tap texel's centre, with that texel's stored depth. A pixel skips the 12 taps only when no edge
// texel (a 3x3 depth step steeper than two texels of depth per texel) lies in any mask texel its
// kernel footprint overlaps, at the level whose texels are as wide as the kernel (a footprint over
// more than 2x2 of them, possible only where that level is capped, takes the kernel); near-grazing
// receivers never skip. Depth-extent masking skips additionally only when the receiver's depth range
// over the kernel lies wholly in front of, or wholly behind, every stored depth in the footprint, so
// it always reproduces the edge-masked result exactly. Masked and unmasked agree except where a
// receiver's tangent plane, extended over the kernel, crosses an edge-free stretch of the map (a
// concave crease, e.g. a wall meeting the roof slab above it): there the full kernel lets a few taps
// through and the single tap does not. Such pixels differ by fewer than half the taps, so they never
// change between lit and shadowed at a 0.5 threshold. With PCSS the footprint tested is the blocker
// search's (where wider than the kernel): every PCSS tap lies within it, since the filter's radius,
// the reach of the average blocker, never exceeds the search's, so the same argument holds; the mask
// level is chosen for the widest search a cascade can need (its depth range times the sun's tangent).
#include "barriers.hpp"
#include "cascades_pass.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <glm/gtc/packing.hpp>

#include "cascade_fit.hpp"
#include "cascade_pipelines.hpp"
#include "light_space.hpp"
#include "shared/cascades.h"
#include "shared/izb.h"
#include "shared/shadows.h"

namespace shadows::detail {

using namespace engine::gpu;
namespace gs = gpu_shared;

namespace {

// A neighbour step steeper than this many texels of depth per texel counts as an edge.
constexpr float kEdgeSlopeTexels = 2.0f;
// Masking::Planes: the mask level whose texels are the depth blocks' (kSmBlock texels a side).
constexpr uint32_t kPlanesLevel = 3;
static_assert((1u << kPlanesLevel) == gs::kSmBlock);

// A mask rectangle (lo.x, lo.y, hi.x, hi.y, inclusive, in mask texels) that no receiver reads, and
// the texels one holds (0 for that one).
const glm::ivec4 kNoRect(0, 0, -1, -1);
uint64_t rect_texels(const glm::ivec4& r) {
  return r.z >= r.x && r.w >= r.y ? uint64_t(r.z - r.x + 1) * uint64_t(r.w - r.y + 1) : 0;
}

uint32_t mip_count(uint32_t size) {
  uint32_t levels = 1;
  while ((size >> levels) > 0) ++levels;
  return levels;
}

// Map-texel xy bounds of `points` in `light_view_projection`.
glm::vec4 texel_bounds(const glm::mat4& light_view_projection, const glm::vec3* points, int n, float size) {
  glm::vec4 r(std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
              -std::numeric_limits<float>::max(), -std::numeric_limits<float>::max());
  for (int i = 0; i < n; ++i) {
    const glm::vec2 t = (glm::vec2(light_view_projection * glm::vec4(points[i], 1.0f)) * 0.5f + 0.5f) * size;
    r = glm::vec4(glm::min(glm::vec2(r), t), glm::max(glm::vec2(r.z, r.w), t));
  }
  return r;
}

// Per-pixel rotations (cos, sin) from a fixed seed, so frames and runs are reproducible.
Image create_rotation_texture(Context& ctx) {
  constexpr uint32_t n = gs::kRotationTileSize;
  std::mt19937 rng(0x0c5ca1du);
  std::uniform_real_distribution<float> angle(0.0f, 6.2831853f);
  std::vector<uint32_t> texels(n * n);
  for (auto& t : texels) {
    const float a = angle(rng);
    t = glm::packHalf2x16(glm::vec2(std::cos(a), std::sin(a)));
  }
  Buffer staging(ctx, texels.size() * 4, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, "cascade rotation staging");
  staging.write(texels.data(), texels.size() * 4);
  Image rotation(ctx, {n, n}, VK_FORMAT_R16G16_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                   "cascade rotation");
  ctx.immediate_submit([&](VkCommandBuffer cmd) {
    rotation.transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_TRANSFER_BIT,
                        VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {n, n, 1};
    vkCmdCopyBufferToImage(cmd, staging.handle(), rotation.handle(), VK_IMAGE_LAYOUT_GENERAL, 1, &copy);
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  });
  return rotation;
}

// Refuses a device without what the cascades' shaders need, before anything is made on it.
Context& with_cascade_features(Context& c) {
  if (!c.features().subgroup_arithmetic_compute_fragment)
    throw VulkanError("the cascades need subgroup arithmetic and ballot operations in compute shaders, which " +
                      c.device_name() + " lacks");
  return c;
}

}  // namespace

struct CascadesPass::Impl {
  explicit Impl(Context& c) : ctx(with_cascade_features(c)), rotation(create_rotation_texture(c)), pipelines(c) {
    params = Buffer(c, sizeof(gs::CascadeParams), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                    false, "cascade params");
    counters = Buffer(c, gs::CASCADE_COUNTER_WORDS * 4,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                          VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                      false, "cascade counters");
    nearest = Sampler(c, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "cascade nearest");
    no_input_list = Buffer(c, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "cascade input list placeholder");
  }

  Context& ctx;
  uint32_t map_size = 0;
  Image depth;        // D32 array, one layer per cascade
  // Per mask texel of each cascade's rectangle, at its mask level: (edge flag, packed [min, max] light
  // depth of the neighbourhood); then the same combined over each texel's 2x2 neighbourhoods, which
  // the filter reads with a single load.
  Buffer masks;
  Buffer neighbourhoods;
  VkDeviceSize mask_capacity = 0;  // texels
  Image rotation;     // kRotationTileSize^2 RG16F (cos, sin)
  Buffer blurred;     // the blur's result per blur-list entry, written back after it
  Buffer work_list;   // one uint per pixel: kernel entries from the front, band entries from the back
  VkExtent2D frame_extent{};
  Buffer params;
  Buffer counters;    // host-readable: counters + indirect dispatch args
  Buffer blur_list;
  Sampler nearest;
  CascadePipelines pipelines;
  Buffer no_input_list;  // bound where the classify stage runs over the frame
  CascadeFit fit;
  ReadbackRing readback;
  bool blur_enabled = false;
  uint32_t drawn = 0;  // cascades whose maps the last record drew (Stats::cascades_drawn)

  void ensure_maps(VkCommandBuffer cmd, uint32_t size) {
    if (map_size == size) return;
    map_size = size;
    // Always kMaxCascades layers: the views stay 2D arrays whatever the cascade count.
    depth = Image(ctx, {size, size}, kCascadeMapFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                  "cascade depth", 1, kMaxCascadeCount);
    to_general(ctx, cmd, depth);
  }

  void ensure_frame(VkExtent2D extent) {
    if (blurred.valid() && frame_extent.width == extent.width && frame_extent.height == extent.height) return;
    frame_extent = extent;
    blurred = Buffer(ctx, std::max<VkDeviceSize>(4, VkDeviceSize(extent.width) * extent.height * 4),
                     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "cascade blurred");
    blur_list = Buffer(ctx, std::max<VkDeviceSize>(4, VkDeviceSize(extent.width) * extent.height * 4),
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "cascade blur list");
    work_list = Buffer(ctx, std::max<VkDeviceSize>(4, VkDeviceSize(extent.width) * extent.height * 4),
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "cascade work list");
  }

  // The mask texels cascade c's receivers can read: the light-space bounds of its view slice (as
  // fitted, blend band included), clipped to the bounds of everything drawn, grown by the kernel,
  // the offsets and the mask's one-texel border. Masks are built only there; the filter takes the
  // full kernel for any footprint outside, so a loose or wrong rectangle costs time, never accuracy.
  glm::ivec4 mask_rect(const Frame& frame, uint32_t c, uint32_t level, float kernel) const {
    const View& view = frame.view;
    const float size = float(map_size);
    const glm::mat4& lvp = fit.light_view_projection[c];
    glm::vec3 corners[8];
    view_slice_corners(view, c == 0 ? fit.splits[0] : fit.blend_start[c - 1], fit.splits[c + 1], corners);
    glm::vec4 r = texel_bounds(lvp, corners, 8, size);
    const Aabb scene = scene_bounds(frame);
    if (scene.valid()) {
      glm::vec3 box[8];
      for (int i = 0; i < 8; ++i)
        box[i] = glm::vec3((i & 1) ? scene.max.x : scene.min.x, (i & 2) ? scene.max.y : scene.min.y,
                           (i & 4) ? scene.max.z : scene.min.z);
      const glm::vec4 b = texel_bounds(lvp, box, 8, size);
      r = glm::vec4(glm::max(glm::vec2(r), glm::vec2(b)), glm::min(glm::vec2(r.z, r.w), glm::vec2(b.z, b.w)));
    }
    // Kernel, normal offsets (in texels; at most one texel each way), snapping, and the border.
    const float margin = kernel + 4.0f;
    const glm::ivec2 lo = glm::ivec2(glm::floor(glm::vec2(r) - margin));
    const glm::ivec2 hi = glm::ivec2(glm::ceil(glm::vec2(r.z, r.w) + margin));
    const int last = int(std::max(map_size >> level, 1u)) - 1;
    const glm::ivec2 a = glm::clamp(lo, glm::ivec2(0), glm::ivec2(int(map_size) - 1)) >> int(level);
    const glm::ivec2 b = glm::clamp(hi, glm::ivec2(0), glm::ivec2(int(map_size) - 1)) >> int(level);
    if (hi.x < 0 || hi.y < 0 || lo.x >= int(map_size) || lo.y >= int(map_size) || r.x > r.z || r.y > r.w)
      return kNoRect;
    return glm::ivec4(glm::min(a, glm::ivec2(last)), glm::min(b, glm::ivec2(last)));
  }

  gs::CascadeParams make_params(const Frame& frame, const CascadeSettings& s, DebugView debug,
                                std::array<uint32_t, kMaxCascadeCount>* levels,
                                std::array<glm::ivec4, kMaxCascadeCount>* rects) const {
    gs::CascadeParams p{};
    const float size = float(map_size);
    const float tan_half_angle = frame.view.light_tan_half_angle;
    p.pcss = glm::vec4(tan_half_angle, gs::kPcssMaxTexels, 0.0f, 0.0f);
    const uint32_t top_level = mip_count(map_size) - 1;
    uint32_t mask_texels = 0;
    for (uint32_t c = 0; c < kMaxCascadeCount; ++c) {
      const uint32_t k = std::min(c, fit.count - 1);  // unused slots repeat the last cascade
      const float texel = fit.texel_world[k];
      const float range = fit.depth_range[k];
      p.light_view_projection[c] = fit.light_view_projection[k];
      p.light_normal_matrix[c] = glm::transpose(glm::inverse(glm::mat4(glm::mat3(fit.light_view_projection[k]))));
      p.split_far[c] = fit.splits[k + 1];
      p.blend_start[c] = fit.blend_start[k];
      p.texel_world[c] = texel;
      p.kernel_texels[c] = std::max(s.kernel_radius, 0.0f) / texel;
      p.depth_range[c] = range;
      // The widest footprint a pixel's taps may cover: with PCSS its search radius for a receiver at
      // the map's far depth (pcss.glsl, pcss_search_radius), when that is wider than the kernel.
      const float kernel = std::max(p.kernel_texels[c], std::min(tan_half_angle * range / texel, gs::kPcssMaxTexels));
      p.depth_bias[c] = s.constant_bias * texel / range;
      p.normal_offset[c] = s.normal_offset * texel;
      p.edge_threshold[c] = kEdgeSlopeTexels * texel / range;
      // Smallest level whose texels are at least as wide as the kernel: its footprint then spans at
      // most 2x2 texels there. Capped so the mask pass's row buffer stays small; a wider kernel then
      // just visits more texels. The planes' level is their blocks'.
      const float width = std::max(2.0f * kernel, 1.0f);
      const uint32_t level =
          s.masking == Masking::Planes ? kPlanesLevel
                                       : std::min({uint32_t(std::ceil(std::log2(width) - 1e-4f)), top_level,
                                                   uint32_t(gs::CASCADE_MASK_MAX_LEVEL)});
      p.mask_level[c] = int(level);
      p.mask_rect[c] = c < fit.count ? mask_rect(frame, c, level, kernel) : kNoRect;
      p.mask_offset[c] = mask_texels;
      mask_texels += uint32_t(rect_texels(p.mask_rect[c]));
      (*levels)[c] = level;
      (*rects)[c] = p.mask_rect[c];
    }
    (void)size;
    const glm::mat4& v = frame.view.view;
    p.camera_position = glm::vec4(frame.view.camera_position, 1.0f);
    p.camera_forward = glm::vec4(-glm::vec3(v[0][2], v[1][2], v[2][2]), 0.0f);
    p.light_direction = glm::vec4(glm::normalize(frame.view.light_direction), 0.0f);
    p.extent = glm::uvec4(frame.view.extent.width, frame.view.extent.height, map_size, fit.count);
    uint32_t masking = gs::CASCADE_MASKING_OFF;
    if (s.masking == Masking::Edge) masking = gs::CASCADE_MASKING_EDGE;
    if (s.masking == Masking::DepthExtent) masking = gs::CASCADE_MASKING_DEPTH_EXTENT;
    if (s.masking == Masking::Planes) masking = gs::CASCADE_MASKING_PLANES;
    uint32_t view = gs::CASCADE_DEBUG_NONE;
    if (debug == DebugView::Cascades) view = gs::CASCADE_DEBUG_CASCADES;
    if (debug == DebugView::ExpensivePath) view = gs::CASCADE_DEBUG_EXPENSIVE;
    p.mode = glm::uvec4(masking, s.blur ? 1u : 0u, view, 0u);
    return p;
  }

  // Indirect dispatch sizes from the counters the previous dispatch wrote.
  void record_dispatch_args(VkCommandBuffer cmd) const {
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    pipelines.args.bind(cmd);
    DescriptorWriter()
        .storage_buffer(gs::CASCADE_ARGS_BINDING_COUNTERS, counters.handle())
        .push(ctx, cmd, pipelines.args);
    vkCmdDispatch(cmd, 1, 1, 1);
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                   VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  }

  // Mask and neighbourhood buffers for every cascade's rectangle.
  void ensure_masks(const gs::CascadeParams& p, const std::array<glm::ivec4, kMaxCascadeCount>& rects);
  void record_masks(Frame& frame, const CascadeSettings& s, const std::array<glm::ivec4, kMaxCascadeCount>& rects);
  void record_filter(Frame& frame, const gs::CascadeParams& p, VkImageView out, const PixelList* only);
  void record_blur(Frame& frame, VkImageView out);

  // Each cascade is drawn only over the texels its receivers can read (the mask rectangle, which
  // already holds the kernel, the offsets and a border, in map texels): the rest of a layer is never
  // sampled, and on a raster-poor GPU the fill is most of this pass.
  void record_depth(Frame& frame, const CascadeSettings& s,
                    const std::array<uint32_t, kMaxCascadeCount>& levels,
                    const std::array<glm::ivec4, kMaxCascadeCount>& rects) {
    VkCommandBuffer cmd = frame.cmd;
    ScopedGpuRegion region(ctx, frame.profiler, cmd, "cascade_depth");
    const Pipeline& pipeline = pipelines.depth[s.cull_front_faces ? 1 : 0];
    for (uint32_t c = 0; c < fit.count; ++c) {
      const glm::ivec4 r = rects[c];
      if (rect_texels(r) == 0) continue;  // no receiver reads this cascade
      const int level = int(levels[c]), last = int(map_size) - 1;
      const glm::ivec2 lo = glm::ivec2(r.x, r.y) << level;
      const glm::ivec2 hi = glm::min(((glm::ivec2(r.z, r.w) + 1) << level) - 1, glm::ivec2(last));
      const VkRect2D area{{lo.x, lo.y}, {uint32_t(hi.x - lo.x + 1), uint32_t(hi.y - lo.y + 1)}};
      begin_depth_rendering(cmd, depth.layer_view(c), depth.extent(), true, &area);
      pipeline.bind(cmd);
      // Constant bias is applied in the filter (scaled per cascade); the rasterizer adds the slope part.
      vkCmdSetDepthBias(cmd, 0.0f, 0.0f, s.slope_bias);
      // A caster wholly outside the drawn rectangle (in light space) cannot touch it.
      const float size = float(map_size);
      const glm::vec4 ndc = glm::vec4(glm::vec2(lo), glm::vec2(hi + 1)) / size * 2.0f - 1.0f;
      auto outside = [&](const DrawItem& d) { return d.bounds.outside_clip(fit.light_view_projection[c], ndc); };
      draw_casters(
          cmd, frame,
          [&](const DrawItem& d, const MeshRange&) {
            gs::CascadeDepthPush push{d.world, fit.light_view_projection[c]};
            pipeline.push_constants(cmd, push);
          },
          CasterSet::Opaque, outside);
      draw_alpha_casters(ctx, cmd, frame, pipelines.alpha_depth, fit.light_view_projection[c], outside);
      vkCmdEndRendering(cmd);
    }
  }
};

// Replaced buffers outlive the frames in flight that use them (Context::defer_releases).
void CascadesPass::Impl::ensure_masks(const gs::CascadeParams& p, const std::array<glm::ivec4, kMaxCascadeCount>& rects) {
  const VkDeviceSize texels =
      std::max<VkDeviceSize>(p.mask_offset[kMaxCascadeCount - 1] + rect_texels(rects[kMaxCascadeCount - 1]), 1);
  if (texels > mask_capacity) {
    mask_capacity = texels + texels / 4;
    masks = Buffer(ctx, mask_capacity * 8, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "cascade masks");
    neighbourhoods = Buffer(ctx, mask_capacity * 32, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false,
                            "cascade mask neighbourhoods");
  }
}

// One dispatch per cascade over the texels its receivers can read, at the one level it uses; then the
// same over their neighbourhoods.
void CascadesPass::Impl::record_masks(Frame& frame, const CascadeSettings& s,
                                      const std::array<glm::ivec4, kMaxCascadeCount>& rects) {
  VkCommandBuffer cmd = frame.cmd;
  const bool extent = s.masking == Masking::DepthExtent;
  const bool planes = s.masking == Masking::Planes;  // one step: each block's plane
  ScopedGpuRegion region(ctx, frame.profiler, cmd, "cascade_masks");
  for (uint32_t combined = 0; combined < (planes ? 1u : 2u); ++combined) {
    // The masks' stores before the neighbourhoods' loads.
    if (combined)
      memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
    const Pipeline& pipeline = pipelines.edges[planes ? 2u : combined];
    pipeline.bind(cmd);
    for (uint32_t c = 0; c < fit.count; ++c) {
      const glm::ivec4 rect = rects[c];
      if (rect_texels(rect) == 0) continue;
      DescriptorWriter()
          .uniform_buffer(gs::CASCADE_MASK_BINDING_PARAMS, params.handle())
          .sampled_image(gs::CASCADE_MASK_BINDING_DEPTH, depth.view(), nearest.handle(), VK_IMAGE_LAYOUT_GENERAL)
          .storage_buffer(gs::CASCADE_MASK_BINDING_MASKS, masks.handle())
          .storage_buffer(gs::CASCADE_MASK_BINDING_NEIGHBOURHOODS, neighbourhoods.handle())
          .push(ctx, cmd, pipeline);
      pipeline.push_constants(cmd, gs::CascadeMaskPush{c, extent ? 1u : 0u, 0u, 0u});
      vkCmdDispatch(cmd, uint32_t(rect.z - rect.x + 8) / 8, uint32_t(rect.w - rect.y + 8) / 8, 1);
    }
  }
  pass_barrier(frame.ctx, cmd);
}

// The filter's stages: classify (over the frame, or over `only`'s list), then the kernel and band
// lists it made, with indirect dispatches.
void CascadesPass::Impl::record_filter(Frame& frame, const gs::CascadeParams& p, VkImageView out, const PixelList* only) {
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(ctx, frame.profiler, cmd, "cascade_filter");
  const uint32_t masking = p.mode.x, debug_view = p.mode.z, pcss = p.pcss.x > 0.0f ? 1u : 0u;
  auto bind_filter = [&](uint32_t stage) {
    const Pipeline& pipeline = pipelines.filter(stage, masking, debug_view, pcss);
    pipeline.bind(cmd);
    DescriptorWriter()
        .uniform_buffer(gs::CASCADE_FILTER_BINDING_PARAMS, params.handle())
        .storage_image(gs::CASCADE_FILTER_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gs::CASCADE_FILTER_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .sampled_image(gs::CASCADE_FILTER_BINDING_DEPTH, depth.view(), nearest.handle(), VK_IMAGE_LAYOUT_GENERAL)
        .storage_buffer(gs::CASCADE_FILTER_BINDING_NEIGHBOURHOODS, neighbourhoods.handle())
        .sampled_image(gs::CASCADE_FILTER_BINDING_ROTATION, rotation.view(), nearest.handle(),
                       VK_IMAGE_LAYOUT_GENERAL)
        .storage_image(gs::CASCADE_FILTER_BINDING_SHADOW_TERM, out)
        .storage_image(gs::CASCADE_FILTER_BINDING_OVERLAY, frame.overlay.view())
        .storage_buffer(gs::CASCADE_FILTER_BINDING_COUNTERS, counters.handle())
        .storage_buffer(gs::CASCADE_FILTER_BINDING_BLUR_LIST, blur_list.handle())
        .storage_buffer(gs::CASCADE_FILTER_BINDING_WORK_LIST, work_list.handle())
        .storage_buffer(gs::CASCADE_FILTER_BINDING_INPUT_LIST, only ? only->entries : no_input_list.handle())
        .storage_buffer(gs::CASCADE_FILTER_BINDING_INPUT_COUNTERS, only ? only->counters : no_input_list.handle())
        .storage_image(gs::CASCADE_FILTER_BINDING_RECEIVERS, frame.gbuffer.albedo)
        .push(ctx, cmd, pipeline);
  };
  if (only) {
    bind_filter(gs::CASCADE_STAGE_CLASSIFY_LIST);
    vkCmdDispatchIndirect(cmd, only->counters, VkDeviceSize(only->count_word + 1) * 4);
  } else {
    bind_filter(gs::CASCADE_STAGE_CLASSIFY);
    // 8x8 invocations of 2x2 pixels each.
    vkCmdDispatch(cmd, (frame.view.extent.width + 15) / 16, (frame.view.extent.height + 15) / 16, 1);
  }
  record_dispatch_args(cmd);
  // The two lists hold different pixels: their stages need no barrier between them.
  bind_filter(gs::CASCADE_STAGE_KERNEL);
  vkCmdDispatchIndirect(cmd, counters.handle(), gs::CASCADE_COUNTER_DISPATCH_KERNEL * 4);
  bind_filter(gs::CASCADE_STAGE_BAND);
  vkCmdDispatchIndirect(cmd, counters.handle(), gs::CASCADE_COUNTER_DISPATCH_BAND * 4);
}

// 5x5 on the pixels whose taps disagreed, into a side buffer, then written back.
void CascadesPass::Impl::record_blur(Frame& frame, VkImageView out) {
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(ctx, frame.profiler, cmd, "cascade_blur");
  record_dispatch_args(cmd);
  gs::CascadeBlurPush push{glm::vec4(frame.view.camera_position, 1.0f),
                           glm::uvec4(frame.view.extent.width, frame.view.extent.height, 0u, 0u)};
  for (int apply = 0; apply < 2; ++apply) {
    if (apply)
      memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                     VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    const Pipeline& pipeline = pipelines.blur[apply];
    pipeline.bind(cmd);
    DescriptorWriter()
        .storage_image(gs::CASCADE_BLUR_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gs::CASCADE_BLUR_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .storage_image(gs::CASCADE_BLUR_BINDING_SHADOW_TERM, out)
        .storage_buffer(gs::CASCADE_BLUR_BINDING_COUNTERS, counters.handle())
        .storage_buffer(gs::CASCADE_BLUR_BINDING_BLUR_LIST, blur_list.handle())
        .storage_buffer(gs::CASCADE_BLUR_BINDING_BLURRED, blurred.handle())
        .push(ctx, cmd, pipeline);
    pipeline.push_constants(cmd, push);
    vkCmdDispatchIndirect(cmd, counters.handle(), gs::CASCADE_COUNTER_DISPATCH_BLUR * 4);
  }
}

CascadesPass::CascadesPass(Context& ctx) : impl_(std::make_unique<Impl>(ctx)) {}

CascadesPass::~CascadesPass() = default;

void CascadesPass::record(Frame& frame, const CascadeSettings& settings, VkImageView out, DebugView debug,
                          const PixelList* only) {
  static_assert(gs::kIzbHybridEntriesPerGroup == 4 * gs::CASCADE_LIST_GROUP, "a list workgroup takes 4 entries a thread");
  Impl& m = *impl_;
  VkCommandBuffer cmd = frame.cmd;
  m.ensure_maps(cmd, std::max(settings.map_size, 16u));
  m.ensure_frame(frame.view.extent);
  m.fit = fit_cascades(frame.view, settings, caster_bounds(frame));
  std::array<uint32_t, kMaxCascadeCount> levels{};
  std::array<glm::ivec4, kMaxCascadeCount> rects{};
  CascadeSettings s = settings;
  if (s.masking == Masking::Auto) s.masking = only ? Masking::Off : Masking::Edge;
  gs::CascadeParams p = m.make_params(frame, s, debug, &levels, &rects);
  if (only) p.mode.w = only->count_word;
  // A pixel reads the cascade its view depth falls in and, in a blend band, the next one: those that
  // end before the nearest listed pixel are read by none, and neither drawn nor masked.
  for (uint32_t c = 0; only && c < m.fit.count; ++c)
    if (m.fit.splits[c + 1] <= only->nearest_view_depth) rects[c] = kNoRect;
  m.drawn = 0;
  for (uint32_t c = 0; c < m.fit.count; ++c) m.drawn += rect_texels(rects[c]) != 0 ? 1u : 0u;
  record_update(m.ctx, cmd, m.params, &p, sizeof(p));
  m.ensure_masks(p, rects);
  m.blur_enabled = settings.blur;

  vkCmdFillBuffer(cmd, m.counters.handle(), 0, gs::CASCADE_COUNTER_WORDS * 4, 0);
  m.record_depth(frame, settings, levels, rects);
  pass_barrier(frame.ctx, cmd);
  if (s.masking != Masking::Off) m.record_masks(frame, s, rects);
  m.record_filter(frame, p, out, only);
  pass_barrier(frame.ctx, cmd);
  if (settings.blur) m.record_blur(frame, out);
  pass_barrier(frame.ctx, cmd);
  // The counters are read on the host once this frame has completed.
  m.readback.record_copy(frame, m.counters, gs::CASCADE_COUNTER_WORDS * 4, pass_shader_stages(m.ctx),
                         VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, "cascade counters readback");
}

void CascadesPass::after_frame(Stats& stats, uint32_t slot) {
  Impl& m = *impl_;
  const Buffer* readback = m.readback.take(slot);
  if (!readback) return;
  const uint32_t* c = readback->as<uint32_t>();
  stats.expensive_path_pixels = c[gs::CASCADE_COUNTER_KERNEL] + c[gs::CASCADE_COUNTER_EXPENSIVE];
  stats.blurred_pixels = m.blur_enabled ? c[gs::CASCADE_COUNTER_BLUR] : 0;
  const uint64_t facing = c[gs::CASCADE_COUNTER_FACING];
  stats.expensive_path_fraction = facing ? double(stats.expensive_path_pixels) / double(facing) : 0.0;
  stats.cascade_splits.assign(m.fit.splits.begin(), m.fit.splits.begin() + m.fit.count + 1);
  stats.cascades_drawn = m.drawn;
}

}  // namespace shadows::detail
