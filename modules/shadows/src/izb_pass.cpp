#include "barriers.hpp"
#include "izb_pass.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "backend_probe.hpp"
#include "csm_pass.hpp"
#include "gpu/profiler.hpp"
#include "light_space.hpp"
#include "shared/frame.h"
#include "shared/izb.h"
#include "shared/local_light.h"
#include "shared/shadow_common.h"

namespace shadows::detail {

using namespace engine::gpu;

namespace {

std::vector<Binding> izb_bindings() {
  using gpu_shared::uint;
  const VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  return {{gpu_shared::IZB_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
          {gpu_shared::IZB_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},  // the frame, at the partials' start
          {gpu_shared::IZB_BINDING_COUNTERS, storage},
          {gpu_shared::IZB_BINDING_HEADS, storage},
          {gpu_shared::IZB_BINDING_FARTHEST, storage},
          {gpu_shared::IZB_BINDING_NODES, storage},
          {gpu_shared::IZB_BINDING_MASK, storage},
          {gpu_shared::IZB_BINDING_PIXEL_STATE, storage},
          {gpu_shared::IZB_BINDING_QUADS, storage},
          {gpu_shared::IZB_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::IZB_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::IZB_BINDING_ALBEDO, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::IZB_BINDING_HYBRID_LIST, storage},
          {gpu_shared::IZB_BINDING_SOFT_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::IZB_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::IZB_BINDING_OVERLAY, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::IZB_BINDING_TRIANGLES, storage},
          {gpu_shared::IZB_BINDING_OVERFLOW_LIST, storage},
          {gpu_shared::IZB_BINDING_CSM_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
          {gpu_shared::IZB_BINDING_OCCLUDER_DISTANCE, storage},
          {gpu_shared::IZB_BINDING_GRID_TRIANGLES, storage},
          {gpu_shared::IZB_BINDING_RECORDS, storage},
          {gpu_shared::IZB_BINDING_PAIRS, storage},
          {gpu_shared::IZB_BINDING_BOUNDS_PARTIALS, storage},
          {gpu_shared::IZB_BINDING_MATERIAL_TEXTURES, storage},
          {gpu_shared::IZB_BINDING_CASTER_DRAWS, storage},
          {gpu_shared::IZB_BINDING_CSM_TEXELS, storage},
          {gpu_shared::IZB_BINDING_TILE_PAIRS, storage},
          {gpu_shared::IZB_BINDING_LIT_WORDS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
          {gpu_shared::IZB_BINDING_LIST_COUNTS, storage},
          {gpu_shared::IZB_BINDING_LIST_CURSOR, storage},
          {gpu_shared::IZB_BINDING_RESOLVE_LIST, storage}};
}

// IZB_FLAG_BOUNDED_FIT: camera_ray at pixel corner (x, y) as an origin and a direction affine in x and
// y (with the inverse view-projection's w row free of x and y, each point's w is one constant), and
// bounds on how far rounding takes the build's rays and the fit's from them, in units of 2^-23 (twice
// float's unit roundoff, u): the build's point is four products summed (4u of their sizes) from a
// corrected NDC quotient (3u of the x and y columns), times 1 / w (u), and its direction the far point
// less the near one (u); the fit's ray is three float terms (2u, and u for the coefficients' own).
void set_corner_rays(gpu_shared::IzbParams& p, const glm::mat4& inverse_vp, VkExtent2D extent) {
  const glm::dmat4 m(inverse_vp);
  const double near_scale = p.ray_scales.x, far_scale = p.ray_scales.y;
  const double unit = std::ldexp(1.0, -23);
  const glm::dvec3 step_x = glm::dvec3(m[0]) * (2.0 / extent.width), step_y = glm::dvec3(m[1]) * (2.0 / extent.height);
  // Pixel corner (0, 0) is NDC (-1, -1); the near point at depth 1, the far one at 0.5 (pixel_corner_points).
  const glm::dvec3 origin = glm::dvec3(-m[0] - m[1] + m[2] + m[3]) * near_scale;
  const glm::dvec3 far_point = glm::dvec3(-m[0] - m[1] + 0.5 * m[2] + m[3]) * far_scale;
  const glm::dvec3 origin_x = step_x * near_scale, origin_y = step_y * near_scale;
  const glm::dvec3 direction = far_point - origin;
  const glm::dvec3 direction_x = step_x * (far_scale - near_scale), direction_y = step_y * (far_scale - near_scale);
  const double w = extent.width, h = extent.height;
  const double origin_size = glm::length(origin) + w * glm::length(origin_x) + h * glm::length(origin_y);
  const double direction_size = glm::length(direction) + w * glm::length(direction_x) + h * glm::length(direction_y);
  const double x_y = glm::length(glm::dvec3(m[0])) + glm::length(glm::dvec3(m[1]));
  const double near_terms = x_y + glm::length(glm::dvec3(m[2])) + glm::length(glm::dvec3(m[3]));
  const double far_terms = x_y + 0.5 * glm::length(glm::dvec3(m[2])) + glm::length(glm::dvec3(m[3]));
  const double build_origin = unit * (std::abs(near_scale) * (2.0 * near_terms + 1.5 * x_y) + 0.5 * origin_size);
  const double build_far = unit * (std::abs(far_scale) * (2.0 * far_terms + 1.5 * x_y) + 0.5 * (origin_size + direction_size));
  const double build_direction = build_origin + build_far + 0.5 * unit * direction_size;
  const double fit_origin = 1.5 * unit * origin_size, fit_direction = 1.5 * unit * direction_size;
  p.corner_ray_origin[0] = glm::vec4(glm::vec3(origin), float(build_origin + fit_origin));
  p.corner_ray_origin[1] = glm::vec4(glm::vec3(origin_x), float(origin_size));
  p.corner_ray_origin[2] = glm::vec4(glm::vec3(origin_y), 0.0f);
  p.corner_ray_direction[0] = glm::vec4(glm::vec3(direction), float(build_direction + fit_direction));
  p.corner_ray_direction[1] = glm::vec4(glm::vec3(direction_x), float(direction_size));
  p.corner_ray_direction[2] = glm::vec4(glm::vec3(direction_y), 0.0f);
}

// The light frustum fit's workgroups over the view (izb_fit.comp).
uint32_t fit_columns(uint32_t width) { return (width + gpu_shared::kIzbFitBlockWidth - 1) / gpu_shared::kIzbFitBlockWidth; }
uint32_t fit_rows(uint32_t height) { return (height + gpu_shared::kIzbFitBlockHeight - 1) / gpu_shared::kIzbFitBlockHeight; }

uint32_t debug_code(DebugView debug) {
  switch (debug) {
    case DebugView::VisibilityMask: return 1;
    case DebugView::ListLength: return 2;
    case DebugView::CsmCoverage: return 4;
    default: return 0;
  }
}
}  // namespace

struct IzbPass::Impl {
  Context& ctx;
  PipelineFactory factory;
  // Every IZB pipeline, specialized for a sample count and a set of IZB_FLAG_* (see izb_common.glsl).
  // The raster trace: software (geometry-shader quads + exact texel test) and hardware conservative
  // rasterization, each also as a count-only variant for the before-culling fragment statistic.
  struct TracePipelines {
    Pipeline software, hardware, count_software, count_hardware;
  };
  struct Pipelines {
    Pipeline fit, setup, build, fallback, list_stats, grid_setup, scan, scatter, list_dispatch;
    Pipeline build_insert;  // valid where the build runs in two steps (izb_build.comp, kBuildStep)
    // Steps 1-3 of the tile work, per work (IZB_WORK_*), made on first use (tile_work_for()) with the
    // set's constants.
    struct TileWork {
      Pipeline records, tile_bin, texel_bin;
    };
    std::array<TileWork, 4> tile_work;
    std::vector<SpecializationConstant> constants;  // the compute trace's workgroup shape, samples, flags
    Pipeline trace_compute;
    TracePipelines trace;
  };
  std::map<uint64_t, std::unique_ptr<Pipelines>> pipeline_sets;
  Pipelines* p = nullptr;  // this frame's
  std::map<uint64_t, Pipeline> resolve_pipelines;  // also per debug view and hybrid

  const Pipeline& resolve_pipeline(uint32_t samples_per_pixel, uint32_t flags, uint32_t debug, bool hybrid) {
    auto& pipeline = resolve_pipelines[(uint64_t(samples_per_pixel) << 40) | (uint64_t(debug) << 33) |
                                       (uint64_t(hybrid) << 32) | flags];
    if (!pipeline.valid())
      pipeline = factory.compute({"izb_resolve.comp", izb_bindings(), sizeof(gpu_shared::IzbComputePush),
                                  {{10, samples_per_pixel}, {11, flags}, {12, debug}, {13, hybrid ? 1u : 0u}}});
    return pipeline;
  }
  Buffer list_counts, list_cursor;  // the cursors' buffer also holds the prefix sum's block sums
  uint32_t scan_blocks = 0;
  // IZB_FLAG_LISTED_RESOLVE: the pixels with nodes (frame-sized where it is on, else a placeholder).
  Buffer resolve_list;
  // Hybrid: the cascades' term and the pixels that blend toward it (frame-sized only in hybrid).
  Image soft_term;
  Buffer hybrid_list;
  VkExtent2D hybrid_extent{};
  Pipeline hybrid_blend;
  Image trace_depth;
  Buffer params, counters;
  // The frame the fit writes (IzbFrame), then its per-workgroup bounds from vec4 kIzbPartialsAt on
  // (izb.h): storage for the fit, a uniform buffer's range for the passes after it.
  Buffer frame_data;
  void make_frame_data(VkDeviceSize fit_groups) {
    frame_data = Buffer(ctx, (gpu_shared::kIzbPartialsAt + fit_groups) * 16,
                        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT |
                            VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                        false, "izb frame and fit bounds per workgroup");
  }
  ReadbackRing counters_readback;
  Buffer heads, farthest, nodes, mask, pixel_state, quads, overflow_list, triangles, occluder_distance;
  Buffer grid_triangles, caster_draw_words, csm_texels;
  // Whether csm_texels' texel view reaches all of its words (IZB_FLAG_LIT_FETCH).
  bool lit_view_whole() const { return csm_texels.size() / 4 <= ctx.properties().limits.maxTexelBufferElements; }
  size_t triangle_capacity = 0;
  uint64_t caster_draw_word_capacity = 0;
  std::vector<uint32_t> first_triangle;  // per frame draw: its first caster triangle (casters only)
  std::vector<uint32_t> caster_items;    // per caster draw, in order: its index in the frame's draws
  std::vector<gpu_shared::IzbCasterDraw> caster_table;  // this frame's caster draws
  std::vector<gpu_shared::IzbCasterDraw> built_table;   // the caster draws `triangles` was built from
  std::vector<Buffer> caster_tables;                    // per frame-in-flight slot: the table the build read
  Pipeline build_casters;
  // Compute trace / CSM work lists (see izb.h), each grown to the demand a frame measured.
  struct WorkList {
    Buffer buffer;
    uint64_t capacity = 0, demand = 0;
  };
  WorkList records, tile_pairs, pairs;
  uint32_t tiles_per_side = 0;
  uint32_t caster_draws = 0;
  BackendProbe trace_probe{"frustum_trace"};
  BackendProbe csm_probe{"csm"};
  // Known-lit culling under LitCulling::Auto: the IZB's own passes timed with the lit map ("on", the
  // probe's raster slot) and without ("off", its compute slot: the choice without timestamps).
  static std::vector<std::string> izb_regions() {
    return {"light_frustum", "lit_map", "csm", "izb_build", "frustum_trace", "izb_fallback", "izb_resolve"};
  }
  BackendProbe lit_probe{izb_regions(), {"on", "off"}};
  // Step 1's shape on a GPU (izb.h): the same passes timed "wide" (the raster slot) and "narrow".
  BackendProbe shape_probe{izb_regions(), {"wide", "narrow"}};
  // IzbSettings::csm_timed: the same passes timed with the automatic CSM prepass ("run", the raster
  // slot) and without it ("skip").
  BackendProbe csm_run_probe{izb_regions(), {"run", "skip"}};
  bool used_compute_trace = false;
  bool used_compute_csm = false;
  bool last_used_lit = false;
  Sampler nearest;
  std::unique_ptr<CsmPass> csm;
  uint32_t resolution = 0;
  uint32_t samples = 0;
  VkExtent2D extent{};
  uint64_t pool_size = 0;
  uint64_t pool_demand = 0;
  uint32_t triangle_count = 0;
  bool used_hardware = false;
  bool last_used_csm = false;

  explicit Impl(Context& c) : ctx(c), factory(c) {
    if (!c.features().subgroup_arithmetic_compute_fragment)
      throw VulkanError("the IZB needs subgroup arithmetic in compute and fragment shaders, which " +
                        c.device_name() + " lacks");
    if (!c.features().depth_clamp)
      throw VulkanError("the IZB trace needs the depthClamp feature, which " + c.device_name() + " lacks");
    params = Buffer(c, sizeof(gpu_shared::IzbParams), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                    false, "izb params");
    make_frame_data(0);
    const VkDeviceSize counter_bytes = gpu_shared::IZB_COUNTER_COUNT * sizeof(uint32_t);
    counters = Buffer(c, counter_bytes,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                          VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                      false, "izb counters");
    nearest = Sampler(c, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "izb nearest");
    csm = std::make_unique<CsmPass>(c);
  }

  // Frame-sized in hybrid; otherwise 1x1 placeholders keep the bindings valid.
  void ensure_hybrid(VkCommandBuffer cmd, VkExtent2D e, bool hybrid) {
    // A frame may shadow the sun with the hybrid and then a local light with the plain IZB: the
    // hybrid's images stay until the extent changes.
    if (!hybrid && soft_term.valid()) return;
    const VkExtent2D want = hybrid ? e : VkExtent2D{1, 1};
    if (soft_term.valid() && want.width == hybrid_extent.width && want.height == hybrid_extent.height) return;
    hybrid_extent = want;
    soft_term = Image(ctx, want, VK_FORMAT_R32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                      "izb hybrid soft term");
    // -1 (not filtered) everywhere; the blend restores that after each frame (izb_hybrid_blend.comp).
    to_general(ctx, cmd, soft_term);
    const VkClearColorValue unfiltered{{-1.0f, 0.0f, 0.0f, 0.0f}};
    const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, soft_term.handle(), VK_IMAGE_LAYOUT_GENERAL, &unfiltered, 1, &range);
    pass_barrier(ctx, cmd);
    hybrid_list = Buffer(ctx, VkDeviceSize(want.width) * want.height * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false,
                         "izb hybrid pixel list");
  }

  // Frame-sized where the resolve is listed; otherwise a placeholder keeps the binding valid.
  void ensure_resolve_list(VkExtent2D e, bool listed) {
    const VkDeviceSize want = listed ? VkDeviceSize(e.width) * e.height * 4 : 4;
    if (resolve_list.valid() && resolve_list.size() >= want) return;
    resolve_list = Buffer(ctx, want, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "izb resolve pixel list");
  }

  // The trace's fragment shader reads gl_PrimitiveID, which SPIR-V puts under the Geometry capability:
  // the hardware conservative trace needs geometry shaders as much as the software one does.
  bool hardware_trace_available() const {
    return ctx.features().conservative_rasterization && ctx.features().geometry_shader;
  }
  bool raster_trace_available() const { return ctx.features().geometry_shader; }
  // A CPU device (lavapipe) pays for every workgroup, idle lane and barrier: it takes other shapes.
  bool cpu_device() const { return ctx.properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU; }

  // The pipelines for `samples` and `flags`, made on first use and kept.
  Pipelines& pipelines(uint32_t samples_per_pixel, uint32_t flags) {
    auto& slot = pipeline_sets[(uint64_t(samples_per_pixel) << 32) | flags];
    if (slot) return *slot;
    slot = std::make_unique<Pipelines>();
    Pipelines& ps = *slot;
    const auto bindings = izb_bindings();
    const uint32_t push = sizeof(gpu_shared::IzbComputePush);
    const std::vector<SpecializationConstant> variant = {{10, samples_per_pixel}, {11, flags}};
    auto compute = [&](const char* shader, std::vector<SpecializationConstant> constants = {}) {
      constants.insert(constants.end(), variant.begin(), variant.end());
      return factory.compute({shader, bindings, push, constants});
    };
    ps.fit = compute("izb_fit.comp");
    if (flags & gpu_shared::IZB_FLAG_CPU_DEVICE) {
      ps.setup = compute("izb_setup.comp");
      ps.list_dispatch = compute("izb_list_dispatch.comp");
    }
    // A CPU device with one node a pixel and a listed resolve: the build classifies every pixel, then
    // inserts the listed ones' nodes in a dispatch over the list (izb_build.comp, kBuildStep).
    const bool build_apart = (flags & gpu_shared::IZB_FLAG_CPU_DEVICE) && (flags & gpu_shared::IZB_FLAG_DIRECT_NODES) &&
                             (flags & gpu_shared::IZB_FLAG_LISTED_RESOLVE);
    ps.build = compute("izb_build.comp", {{14, build_apart ? 1u : 0u}});
    if (build_apart) ps.build_insert = compute("izb_build.comp", {{14, 2u}});
    ps.fallback = compute("izb_fallback.comp");
    ps.list_stats = compute("izb_list_stats.comp");
    ps.grid_setup = compute("izb_triangles.comp");
    ps.scan = compute("izb_scan.comp");
    ps.scatter = compute("izb_scatter.comp");
    // Workgroup shapes of the compute trace and CSM (see izb.h): a CPU device pays per workgroup.
    const bool cpu = cpu_device();
    const std::vector<SpecializationConstant> shape = {
        {0, cpu ? 8u : 32u * gpu_shared::kIzbTileStepRecordsGpu},
        {1, cpu ? gpu_shared::kIzbRecordsPerGroupCpu : gpu_shared::kIzbRecordsPerGroupGpu},
        {2, cpu ? gpu_shared::kIzbTilePairsPerGroupCpu : gpu_shared::kIzbTilePairsPerGroupGpu},
        {4, cpu ? 1u : gpu_shared::kIzbTileStepRecordsGpu}};
    ps.constants = shape;
    ps.constants.insert(ps.constants.end(), variant.begin(), variant.end());
    ps.trace_compute = compute("izb_trace.comp", shape);
    ps.trace = trace_pipelines(samples_per_pixel, flags);
    return ps;
  }

  // Opaque casters' raster trace where some are alpha-tested (see record()), made on first use.
  std::map<uint64_t, TracePipelines> opaque_traces;
  const TracePipelines& opaque_trace_pipelines(uint32_t samples_per_pixel, uint32_t flags) {
    auto [it, fresh] = opaque_traces.try_emplace((uint64_t(samples_per_pixel) << 32) | flags);
    if (fresh) it->second = trace_pipelines(samples_per_pixel, flags & ~gpu_shared::IZB_FLAG_ALPHA);
    return it->second;
  }

  TracePipelines trace_pipelines(uint32_t samples_per_pixel, uint32_t flags) {
    TracePipelines tp;
    const std::vector<SpecializationConstant> variant = {{10, samples_per_pixel}, {11, flags}};
    // Depth: the attachment holds each texel's farthest node; the rasterized depth, biased by minus
    // one slope unit, is the triangle plane's nearest depth over the texel, so LESS culls exactly the
    // fragments behind every node. Depth clamp keeps biased depths below 0 from being clipped.
    GraphicsPipelineDesc trace;
    trace.bindings = izb_bindings();
    trace.push_constant_size = sizeof(gpu_shared::IzbDrawPush);
    trace.vertex_input = VertexInput::PositionOnly;
    trace.cull_mode = VK_CULL_MODE_NONE;
    trace.depth_format = VK_FORMAT_D32_SFLOAT;
    trace.depth_test = true;
    trace.depth_write = false;
    trace.depth_compare = VK_COMPARE_OP_LESS;
    trace.dynamic_depth_compare = true;
    trace.depth_bias = true;
    trace.depth_clamp = true;
    trace.fragment_shader = "izb_trace.frag";
    trace.vertex_shader = "izb_trace.vert";
    auto raster = [&](const std::string& name, uint32_t software, uint32_t count_only) {
      trace.name = name;
      trace.specialization = {{0, software}, {1, count_only}};
      trace.specialization.insert(trace.specialization.end(), variant.begin(), variant.end());
      return factory.graphics(trace);
    };
    if (ctx.features().geometry_shader) {
      trace.geometry_shader = "izb_trace.geom";
      tp.software = raster("izb trace (software conservative)", 1, 0);
      tp.count_software = raster("izb fragment count (software conservative)", 1, 1);
    }
    if (hardware_trace_available()) {
      trace.geometry_shader.clear();
      trace.conservative = ConservativeMode::Overestimate;
      tp.hardware = raster("izb trace (hardware conservative)", 0, 0);
      tp.count_hardware = raster("izb fragment count (hardware conservative)", 0, 1);
    }
    return tp;
  }

  void ensure_buffers(const Frame& frame, const IzbSettings& s) {
    const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    const uint32_t spp = s.samples_per_pixel == 32 ? 32 : 1;
    if (resolution != s.resolution) {
      resolution = s.resolution;
      const VkDeviceSize texels = VkDeviceSize(resolution) * resolution;
      heads = Buffer(ctx, texels * 4, usage, false, "izb heads");
      list_counts = Buffer(ctx, texels * 4, usage, false, "izb sorted list counts");
      scan_blocks = uint32_t((texels + gpu_shared::kIzbScanBlock - 1) / gpu_shared::kIzbScanBlock);
      list_cursor = Buffer(ctx, (texels + scan_blocks) * 4, usage, false, "izb sorted list fill cursors and block sums");
      tiles_per_side = (resolution + gpu_shared::kIzbTile - 1) / gpu_shared::kIzbTile;
      // The compute CSM's depths, then the lit map's texels, texel corners and tile records (izb.h;
      // one binding for all).
      const VkDeviceSize tile_words = 8 * VkDeviceSize(tiles_per_side) * tiles_per_side;
      const VkDeviceSize lit_words = gpu_shared::izb_lit_tile_records_at(resolution) + tile_words;
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
      to_general(ctx, frame.cmd, trace_depth);
    }
    const VkExtent2D e = frame.view.extent;
    const VkDeviceSize pixels = VkDeviceSize(e.width) * e.height;
    if (e.width != extent.width || e.height != extent.height || spp != samples) {
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
      nodes = Buffer(ctx, std::max<uint64_t>(pool_size, 1) * 8, usage, false, "izb nodes");
    }
  }

  // The world-space caster triangles, in draw order (the raster trace finds a fragment's triangle as
  // its draw's first triangle plus the primitive index), written on the GPU from the module's geometry
  // and a table of the caster draws; each triangle also knows its caster draw, for the per-frame CSM
  // choice, and what its alpha test needs. Rebuilt only when the table changed (casters moved, came,
  // went or changed material): moving casters cost a small table upload and one dispatch. Buffers
  // only grow. Also finds each caster draw's first triangle (for the raster trace's push constants).
  // Where the caster triangles are read: the compute passes and the raster trace's fragment and (where
  // the device has them) geometry shaders.
  VkPipelineStageFlags2 triangle_readers() const {
    return VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT |
           (ctx.features().geometry_shader ? VK_PIPELINE_STAGE_2_GEOMETRY_SHADER_BIT : 0);
  }

  void ensure_triangles(const Frame& frame) {
    first_triangle.assign(frame.draws.size(), 0);
    caster_table.clear();
    caster_items.clear();
    uint32_t caster_triangles = 0;
    for (size_t i = 0; i < frame.draws.size(); ++i) {
      const DrawItem& d = frame.draws[i];
      if (!d.shadow.casts_shadow) continue;
      const MeshRange& range = frame.geometry.mesh(d.mesh);
      gpu_shared::IzbCasterDraw c{};
      c.world = d.world;
      c.first_index = range.first_index;
      c.vertex_offset = range.vertex_offset;
      c.triangle_count = range.index_count / 3;
      c.first_triangle = caster_triangles;
      c.ordinal = uint32_t(caster_table.size());
      c.alpha_threshold = d.alpha_threshold;
      c.texture = d.base_color_texture;
      caster_table.push_back(c);
      first_triangle[i] = caster_triangles;
      caster_items.push_back(uint32_t(i));
      caster_triangles += c.triangle_count;
    }
    caster_draws = uint32_t(caster_table.size());
    triangle_count = caster_triangles;
    // Flags, bounds and the frustum's draws per caster draw, then the listed triangles (izb.h).
    const uint64_t words = 11 * uint64_t(caster_table.size()) + triangle_count;
    if (words > caster_draw_word_capacity || !caster_draw_words.valid()) {
      caster_draw_word_capacity = std::max<uint64_t>(words, 1);
      caster_draw_words = Buffer(ctx, caster_draw_word_capacity * sizeof(uint32_t),
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false,
                                 "izb caster draws");
      built_table.clear();  // a new buffer holds no bounds yet
    }
    // Mesh ranges are never reused (the geometry only grows), so an equal table means equal triangles.
    const size_t table_bytes = caster_table.size() * sizeof(gpu_shared::IzbCasterDraw);
    // (A frame without casters has empty tables, whose data() may be null: memcmp must not see them.)
    if (triangles.valid() && built_table.size() == caster_table.size() &&
        (table_bytes == 0 || std::memcmp(built_table.data(), caster_table.data(), table_bytes) == 0))
      return;
    if (triangle_count > triangle_capacity || !triangles.valid()) {
      triangle_capacity = std::max<size_t>(triangle_count, 1);
      triangles = Buffer(ctx, triangle_capacity * sizeof(gpu_shared::IzbCasterTriangle),
                         VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "izb caster triangles");
      // 3 vec4 per triangle, then (spot lights) a list of the triangles traced apart.
      grid_triangles = Buffer(ctx, triangle_capacity * 4 * sizeof(glm::vec4), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false,
                              "izb grid-space caster triangles");
    }
    built_table = caster_table;
    if (triangle_count == 0) return;
    // The light-frustum cull's bounds, in the command stream (earlier frames' passes still read the
    // old ones; record_update orders them).
    std::vector<gpu_shared::IzbDrawBounds> bounds;
    bounds.reserve(caster_table.size());
    for (size_t k = 0; k < caster_table.size(); ++k) {
      const DrawItem& d = frame.draws[caster_items[k]];
      const gpu_shared::IzbCasterDraw& c = caster_table[k];
      gpu_shared::IzbDrawBounds b{};
      const bool bounded = d.bounds.valid() && std::isfinite(d.bounds.min.x + d.bounds.min.y + d.bounds.min.z) &&
                           std::isfinite(d.bounds.max.x + d.bounds.max.y + d.bounds.max.z);
      b.lo = glm::vec4(bounded ? d.bounds.min : glm::vec3(1.0f), 0.0f);
      b.hi = glm::vec4(bounded ? d.bounds.max : glm::vec3(-1.0f), 0.0f);  // lo > hi: never culled
      std::memcpy(&b.lo.w, &c.first_triangle, 4);
      std::memcpy(&b.hi.w, &c.triangle_count, 4);
      bounds.push_back(b);
    }
    record_update(ctx, frame.cmd, caster_draw_words, bounds.data(), bounds.size() * sizeof(bounds[0]),
                  caster_table.size() * sizeof(uint32_t));
    // The table in this frame-in-flight slot's own host buffer: the frame that last read it (the
    // slot's previous one) has completed, so it is rewritten and, when too small, replaced freely.
    if (caster_tables.size() <= frame.slot) caster_tables.resize(frame.slot + 1);
    Buffer& table = caster_tables[frame.slot];
    if (!table.valid() || table.size() < table_bytes)
      table = Buffer(ctx, std::max<VkDeviceSize>(table_bytes, table.size() * 2), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                     true, "izb caster draw table");
    table.write(caster_table.data(), table_bytes);  // made visible to the device by the submission
    if (!build_casters.valid())
      build_casters = factory.compute({"izb_casters.comp",
                                       {{gpu_shared::IZB_CASTERS_BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                        {gpu_shared::IZB_CASTERS_BINDING_INDICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                        {gpu_shared::IZB_CASTERS_BINDING_DRAWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                        {gpu_shared::IZB_CASTERS_BINDING_TRIANGLES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
                                       sizeof(gpu_shared::IzbCastersPush)});
    VkCommandBuffer cmd = frame.cmd;
    ScopedGpuRegion region(ctx, frame.profiler, cmd, "izb_casters");
    // Earlier frames' reads of the triangles (compute passes, the raster trace's geometry and fragment
    // shaders) finish before they are overwritten.
    memory_barrier(cmd, triangle_readers(), 0, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0);
    build_casters.bind(cmd);
    DescriptorWriter()
        .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_VERTICES, frame.geometry.vertices().handle())
        .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_INDICES, frame.geometry.indices().handle())
        .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_DRAWS, table.handle())
        .storage_buffer(gpu_shared::IZB_CASTERS_BINDING_TRIANGLES, triangles.handle())
        .push(ctx, cmd, build_casters);
    const uint32_t groups = (triangle_count + 63) / 64;
    const uint32_t groups_x = std::min(groups, ctx.properties().limits.maxComputeWorkGroupCount[0]);
    const gpu_shared::IzbCastersPush push{caster_draws, triangle_count, groups_x, 0u};
    build_casters.push_constants(cmd, push);
    vkCmdDispatch(cmd, groups_x, (groups + groups_x - 1) / groups_x, 1);
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, triangle_readers(),
                   VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  }

  // The compute passes' work lists: first sized from the scene and grid, then grown to the demand a
  // frame measured (a frame that overflows still finishes exactly, only slower). Unused (raster
  // passes only): small placeholders keep every binding valid.
  void ensure_work_lists(bool used) {
    auto ensure = [&](WorkList& list, uint64_t initial, VkDeviceSize stride, const char* name) {
      const uint64_t want = used ? std::max(initial, list.demand) : 1;
      if (list.buffer.valid() && want <= list.capacity) return;
      list.capacity = want;
      list.buffer = Buffer(ctx, want * stride, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, name);
    };
    const uint64_t tiles = uint64_t(tiles_per_side) * tiles_per_side;
    ensure(records, std::max<uint64_t>(uint64_t(triangle_count) * 2, 16384), 16, "izb tile-row records");
    ensure(tile_pairs, std::max<uint64_t>({uint64_t(triangle_count) * 4, tiles * 4, 65536}), 8, "izb tile pairs");
    ensure(pairs, std::max<uint64_t>({uint64_t(triangle_count) * 4, uint64_t(resolution) * resolution / 2, 65536}), 8,
           "izb texel pairs");
  }

  void push_all(VkCommandBuffer cmd, const Frame& frame, const Pipeline& p) {
    DescriptorWriter()
        .uniform_buffer(gpu_shared::IZB_BINDING_PARAMS, params.handle())
        .uniform_buffer(gpu_shared::IZB_BINDING_FRAME, frame_data.handle(), 0, sizeof(gpu_shared::IzbFrame))
        .storage_buffer(gpu_shared::IZB_BINDING_COUNTERS, counters.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_HEADS, heads.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_FARTHEST, farthest.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_NODES, nodes.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_MASK, mask.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_PIXEL_STATE, pixel_state.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_QUADS, quads.handle())
        .storage_image(gpu_shared::IZB_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gpu_shared::IZB_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .storage_image(gpu_shared::IZB_BINDING_ALBEDO, frame.gbuffer.albedo)
        .storage_buffer(gpu_shared::IZB_BINDING_HYBRID_LIST, hybrid_list.handle())
        .storage_image(gpu_shared::IZB_BINDING_SOFT_TERM, soft_term.view())
        .storage_image(gpu_shared::IZB_BINDING_SHADOW_TERM, frame.shadow_term.view())
        .storage_image(gpu_shared::IZB_BINDING_OVERLAY, frame.overlay.view())
        .storage_buffer(gpu_shared::IZB_BINDING_TRIANGLES, triangles.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_OVERFLOW_LIST, overflow_list.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_OCCLUDER_DISTANCE, occluder_distance.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_GRID_TRIANGLES, grid_triangles.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_RECORDS, records.buffer.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_TILE_PAIRS, tile_pairs.buffer.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_PAIRS, pairs.buffer.handle())
        .uniform_texel_buffer(gpu_shared::IZB_BINDING_LIT_WORDS, csm_texels.texel_view())
        .storage_buffer(gpu_shared::IZB_BINDING_LIST_COUNTS, list_counts.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_LIST_CURSOR, list_cursor.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_RESOLVE_LIST, resolve_list.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_BOUNDS_PARTIALS, frame_data.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_MATERIAL_TEXTURES, frame.geometry.textures().handle())
        .storage_buffer(gpu_shared::IZB_BINDING_CASTER_DRAWS, caster_draw_words.handle())
        .storage_buffer(gpu_shared::IZB_BINDING_CSM_TEXELS, csm_texels.handle())
        .sampled_image(gpu_shared::IZB_BINDING_CSM_DEPTH, csm->depth_view(), nearest.handle(), VK_IMAGE_LAYOUT_GENERAL)
        .push(ctx, cmd, p);
  }

  void bind_compute(VkCommandBuffer cmd, const Frame& frame, const Pipeline& p,
                    const gpu_shared::IzbComputePush& push) {
    p.bind(cmd);
    push_all(cmd, frame, p);
    p.push_constants(cmd, push);
  }

  void dispatch(VkCommandBuffer cmd, const Frame& frame, const Pipeline& p,
                gpu_shared::IzbComputePush push, uint32_t x, uint32_t y = 1) {
    bind_compute(cmd, frame, p, push);
    vkCmdDispatch(cmd, x, y, 1);
  }

  void dispatch_pixels(VkCommandBuffer cmd, const Frame& frame, const Pipeline& p,
                       gpu_shared::IzbComputePush push) {
    dispatch(cmd, frame, p, push, (frame.view.extent.width + 7) / 8, (frame.view.extent.height + 7) / 8);
  }

  // A CPU device: the dispatch over list `which` (IZB_LIST_*) from its length, visible to what follows.
  void size_list_dispatch(VkCommandBuffer cmd, const Frame& frame, gpu_shared::IzbComputePush push, uint32_t which) {
    push.mode = which;
    dispatch(cmd, frame, p->list_dispatch, push, 1);
    pass_barrier(frame.ctx, cmd);
  }

  void dispatch_indirect(VkCommandBuffer cmd, const Frame& frame, const Pipeline& p,
                         gpu_shared::IzbComputePush push, uint32_t counter) {
    bind_compute(cmd, frame, p, push);
    vkCmdDispatchIndirect(cmd, counters.handle(), VkDeviceSize(counter) * 4);
  }

  // This frame's pipelines of steps 1-3 for `mode` (IZB_WORK_*).
  const Pipelines::TileWork& tile_work_for(uint32_t mode) {
    Pipelines::TileWork& w = p->tile_work.at(mode);
    if (w.records.valid()) return w;
    std::vector<SpecializationConstant> constants = p->constants;
    constants.push_back({5, mode});
    const auto bindings = izb_bindings();
    const uint32_t push = sizeof(gpu_shared::IzbComputePush);
    w.records = factory.compute({"izb_records.comp", bindings, push, constants});
    w.tile_bin = factory.compute({"izb_tile_bin.comp", bindings, push, constants});
    w.texel_bin = factory.compute({"izb_texel_bin.comp", bindings, push, constants});
    return w;
  }

  // Compute trace / compute CSM, steps 1-3 (see izb.h) for `mode` (IZB_WORK_*); with `time_steps`
  // (IzbSettings::step_timings) each step in a nested profiler region "<region>_records",
  // "<region>_tiles", "<region>_texels".
  void record_tile_work(VkCommandBuffer cmd, const Frame& frame, gpu_shared::IzbComputePush push,
                        uint32_t mode, const std::string& region, bool time_steps) {
    push.mode = mode;
    // The dispatches of steps 2 and 3 (and the trace's step 4) are raised by the steps before them as
    // they append (izb_group_reserve.glsl): no pass between sizes them.
    const uint32_t records_dispatch = gpu_shared::izb_step_dispatch_at(mode);
    const Pipelines::TileWork& tile_work = tile_work_for(mode);
    {
      OptionalGpuRegion step(time_steps, ctx, frame.profiler, cmd, region + "_records");
      // Over the frustum's triangles: the listed ones are fewer (izb_triangles.comp).
      dispatch_indirect(cmd, frame, tile_work.records, push, gpu_shared::IZB_COUNTER_STEP_ONE_DISPATCH);
    }
    pass_barrier(frame.ctx, cmd);
    {
      OptionalGpuRegion step(time_steps, ctx, frame.profiler, cmd, region + "_tiles");
      dispatch_indirect(cmd, frame, tile_work.tile_bin, push, records_dispatch);
    }
    pass_barrier(frame.ctx, cmd);
    OptionalGpuRegion step(time_steps, ctx, frame.profiler, cmd, region + "_texels");
    dispatch_indirect(cmd, frame, tile_work.texel_bin, push, records_dispatch + 3u);
  }
};

IzbPass::IzbPass(Context& ctx) : impl_(std::make_unique<Impl>(ctx)) {}
IzbPass::~IzbPass() = default;

bool IzbPass::hardware_raster_available() const { return impl_->hardware_trace_available(); }

bool IzbPass::csm_test_supported(CsmTest test, std::string* why) const { return impl_->csm->supported(test, why); }

void IzbPass::record(Frame& frame, const IzbSettings& settings, DebugView debug, bool hybrid,
                     bool collect_stats, float soft_distance) {
  Impl& m = *impl_;
  VkCommandBuffer cmd = frame.cmd;
  if (settings.resolution == 0 || settings.resolution > 16384)
    throw std::invalid_argument("IZB resolution must be in 1..16384");
  m.ensure_buffers(frame, settings);
  m.ensure_hybrid(frame.cmd, frame.view.extent, hybrid);
  m.ensure_triangles(frame);
  bool run_csm = m.csm->plan(frame, settings, m.resolution);
  m.csm->prepare(frame.cmd, run_csm ? m.resolution : 1);

  // Raster or compute, per pass. The timing of either depends on the sizes, the scene and the mode.
  // The render size counts in half-octaves of pixels, so dynamic resolution's small steps do not
  // restart the probe every few frames; the CSM setting counts, not whether the adaptive CSM ran
  // this frame (that alternates).
  const double pixels = double(frame.view.extent.width) * frame.view.extent.height;
  uint64_t key = mix_key(0, m.resolution);
  for (uint64_t v : {uint64_t(std::lround(2.0 * std::log2(std::max(pixels, 1.0)))), uint64_t(m.samples),
                     uint64_t(m.triangle_count), uint64_t(settings.csm), uint64_t(settings.csm_test),
                     uint64_t(settings.depth_cull), uint64_t(settings.progressive_removal), uint64_t(hybrid),
                     uint64_t(settings.lit_culling), uint64_t(settings.csm_timed),
                     uint64_t(settings.step_one_shape), uint64_t(settings.anchored_nodes)})
    key = mix_key(key, v);
  const bool raster_trace_available = m.raster_trace_available();
  // A spot light's perspective grid is traced and culled by the compute passes, which read the
  // grid-space triangles (the raster passes' geometry stage assumes the sun's orthographic one).
  const bool spot = frame.view.local_light;
  if (spot && (settings.trace == PassBackend::Raster || (run_csm && settings.csm_backend == PassBackend::Raster)))
    throw std::runtime_error("spot lights take the compute IZB trace and CSM (IzbSettings trace/csm_backend raster)");
  if (spot && run_csm && !CsmPass::compute_available(settings.csm_test))
    throw std::runtime_error("spot lights take the compute CSM, which CSM test " + csm_test_name(settings.csm_test) +
                             " does not have");
  const bool use_compute_trace =
      spot || m.trace_probe.pick(settings.trace, raster_trace_available, true, key, frame.profiler, frame.slot) ==
                  PassBackend::Compute;
  if (!use_compute_trace && !raster_trace_available)
    throw std::runtime_error("the raster IZB trace needs geometry shaders, which " + m.ctx.device_name() +
                             " lacks (use the compute trace)");
  bool use_compute_csm = false;
  if (run_csm) {
    const bool raster_ok = m.csm->raster_available(settings.csm_test);
    const bool compute_ok = CsmPass::compute_available(settings.csm_test);
    if (settings.csm_backend == PassBackend::Compute && !compute_ok)
      throw std::runtime_error("CSM test " + csm_test_name(settings.csm_test) + " has no compute pass");
    if (settings.csm_backend == PassBackend::Raster && !raster_ok)
      throw std::runtime_error("CSM test " + csm_test_name(settings.csm_test) + " has no raster pass on " +
                               m.ctx.device_name() + " (it needs geometry shaders)");
    use_compute_csm = spot || m.csm_probe.pick(settings.csm_backend, raster_ok, compute_ok, key, frame.profiler,
                                               frame.slot) == PassBackend::Compute;
  }
  // Step 1's shape (izb.h, kIzbStepOne*): on a GPU timed both ways once the backends are chosen, where
  // the compute trace or CSM runs its tile work.
  const bool backends_chosen = !m.trace_probe.probing() && !(run_csm && m.csm_probe.probing());
  uint32_t step_one_shape = gpu_shared::kIzbStepOneWide;
  if (settings.step_one_shape != StepOneShape::Auto) {
    if (settings.step_one_shape == StepOneShape::Narrow) step_one_shape = gpu_shared::kIzbStepOneNarrow;
  } else if (m.cpu_device()) {
    step_one_shape = gpu_shared::kIzbStepOneCpu;
  } else if (backends_chosen && (use_compute_trace || use_compute_csm) &&
             m.shape_probe.pick(PassBackend::Auto, true, true, key, frame.profiler, frame.slot) == PassBackend::Compute) {
    step_one_shape = gpu_shared::kIzbStepOneNarrow;
  }
  // Whether the automatic prepass pays for itself here: timed once the above are chosen.
  if (run_csm && settings.csm_timed && m.csm->automatic_only() && backends_chosen && !m.shape_probe.probing() &&
      m.csm_run_probe.pick(PassBackend::Auto, true, true, key, frame.profiler, frame.slot) == PassBackend::Compute) {
    m.csm->skip("skipped: the IZB's passes timed faster without it (IzbSettings::csm_timed)");
    run_csm = false;
    use_compute_csm = false;
  }
  const bool use_hardware = settings.raster == ConservativeRaster::Hardware ||
                            (settings.raster == ConservativeRaster::Auto && m.hardware_trace_available());
  if (!use_compute_trace) {
    if (use_hardware && !m.ctx.features().conservative_rasterization)
      throw std::runtime_error("hardware conservative rasterization requested but " + m.ctx.device_name() +
                               " lacks VK_EXT_conservative_rasterization");
    if (use_hardware && !m.ctx.features().geometry_shader)
      throw std::runtime_error("the hardware conservative trace reads gl_PrimitiveID, which needs geometry shaders, "
                               "which " + m.ctx.device_name() + " lacks");
    if (!use_hardware && !m.ctx.features().geometry_shader)
      throw std::runtime_error("software conservative rasterization needs geometry shaders, which " +
                               m.ctx.device_name() + " lacks");
  }
  m.used_hardware = use_hardware && !use_compute_trace;
  m.used_compute_trace = use_compute_trace;
  m.used_compute_csm = use_compute_csm;
  m.last_used_csm = run_csm;
  // Known-lit culling: the lit map is the sun's alone. Auto probes it once the trace's and the CSM's
  // choices are made, so the frames it compares differ in nothing else.
  bool lit = false;
  if (!spot) {
    if (settings.lit_culling == LitCulling::On) {
      lit = true;
    } else if (settings.lit_culling == LitCulling::Auto && backends_chosen && !m.shape_probe.probing() &&
               !m.csm_run_probe.probing()) {
      lit = m.lit_probe.pick(PassBackend::Auto, true, true, key, frame.profiler, frame.slot) == PassBackend::Raster;
    }
  }
  m.last_used_lit = lit;
  m.ensure_work_lists(use_compute_trace || use_compute_csm || lit);
  if (use_compute_csm) {
    // Per caster draw: whether it enters the CSM this frame.
    const auto& chosen = m.csm->chosen_draws();
    std::vector<uint32_t> flags;
    flags.reserve(m.caster_draws);
    for (const uint32_t i : m.caster_items)
      flags.push_back(i < chosen.size() && chosen[i] ? gpu_shared::IZB_DRAW_IN_CSM : 0u);
    // In the command stream: each frame in flight reads its own flags.
    if (!flags.empty()) record_update(m.ctx, frame.cmd, m.caster_draw_words, flags.data(), flags.size() * sizeof(uint32_t));
  }

  // CPU side of the frustum: the light's rotation and the casters' depth range along it. A spot
  // light: its view from its position, near where a ray inside its cone is within the light's radius
  // (so what lies nearer never counts, local_light.h), far at its range (no point it reaches is
  // farther, nor anything between such a point and the light).
  glm::mat4 light_view = light_view_matrix(frame.view.light_direction);
  const Aabb depth_box = scene_bounds(frame);  // casters and receivers
  float near_d = 0.0f, far_d = 1.0f;
  float tan_half = 0.0f;
  if (spot) {
    light_view = light_view * glm::translate(glm::mat4(1.0f), -frame.view.light_position);
    const float cos_outer = std::clamp(frame.view.light_cos_outer, 0.05f, 1.0f);
    // The near plane sits at 1/64 of the range, not at the bulb: a perspective depth in [0, 1] keeps
    // about far / near ulps of relative precision, and a bulb-sized near plane left the node test's depths
    // of a room-scale light (tens of units) too coarse for its shadow-ray offsets (speckled false
    // shadow). The few casters nearer than it are ray-tested in world space (izb_triangles.comp).
    near_d = std::max(gpu_shared::local_light_bulb(frame.view.light_range) * cos_outer,
                      frame.view.light_range * gpu_shared::kLocalLightNearPerRange);
    far_d = frame.view.light_range;
    tan_half = std::tan(std::acos(cos_outer)) * 1.02f;  // the cone's rim inside the grid
  } else if (depth_box.valid()) {
    float lo = std::numeric_limits<float>::max(), hi = -lo;
    for (int i = 0; i < 8; ++i) {
      glm::vec3 corner((i & 1) ? depth_box.max.x : depth_box.min.x, (i & 2) ? depth_box.max.y : depth_box.min.y,
                       (i & 4) ? depth_box.max.z : depth_box.min.z);
      const float d = -(light_view * glm::vec4(corner, 1.0f)).z;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    const float margin = 0.01f * (hi - lo) + 1e-3f;
    near_d = lo - margin;
    far_d = hi + margin;
  }

  uint32_t flags = collect_stats ? gpu_shared::IZB_FLAG_STATS : 0u;
  if (!settings.depth_cull) flags |= gpu_shared::IZB_FLAG_NO_DEPTH_CULL;
  if (use_compute_csm) flags |= gpu_shared::IZB_FLAG_CSM_BUFFER;
  const bool sorted = settings.lists == ListLayout::Sorted;
  if (sorted) flags |= gpu_shared::IZB_FLAG_SORTED_LISTS;
  if (run_csm) flags |= gpu_shared::IZB_FLAG_CSM;
  // At 32 spp also unasked, unless the hybrid blends by occluder distance (which needs every occluder
  // of a shadowed pixel): its 32 samples are often all shadowed long before its last node is tested
  // (Sponza v1 4K: the trace 0.49 -> 0.44 ms on an H100).
  const bool gaps = hybrid && soft_distance > 0.0f;
  if (settings.progressive_removal || (m.samples == 32 && !gaps)) flags |= gpu_shared::IZB_FLAG_PROGRESSIVE;
  if (lit) flags |= gpu_shared::IZB_FLAG_LIT;
  if (std::any_of(frame.draws.begin(), frame.draws.end(),
                  [](const DrawItem& d) { return d.shadow.casts_shadow && d.alpha_tested(); }))
    flags |= gpu_shared::IZB_FLAG_ALPHA;
  if (gaps) flags |= gpu_shared::IZB_FLAG_GAPS;
  if (m.samples == 1 && !sorted && m.pool_size >= uint64_t(frame.view.extent.width) * frame.view.extent.height)
    flags |= gpu_shared::IZB_FLAG_DIRECT_NODES;
  if ((flags & gpu_shared::IZB_FLAG_DIRECT_NODES) && !m.cpu_device())
    flags |= gpu_shared::IZB_FLAG_ROW_RUNS;
  const bool all_triangles = m.triangle_count <= gpu_shared::kIzbAllTrianglesLimit;
  if (all_triangles) flags |= gpu_shared::IZB_FLAG_ALL_TRIANGLES;
  const bool triangles_in_trace = all_triangles && use_compute_trace && !run_csm && !lit && !spot;
  if (triangles_in_trace) flags |= gpu_shared::IZB_FLAG_TRIANGLES_IN_TRACE;
  const bool cpu = m.cpu_device();
  if (cpu) flags |= gpu_shared::IZB_FLAG_CPU_DEVICE;
  if (cpu && lit && m.lit_view_whole()) flags |= gpu_shared::IZB_FLAG_LIT_FETCH;
  // The resolve is needed only to count samples (32 spp), blend (hybrid), draw a debug view, or for a
  // local light's straddling casters and cone faces.
  const bool direct_term = m.samples == 1 && !hybrid && debug_code(debug) == 0 && !spot;
  if (direct_term) flags |= gpu_shared::IZB_FLAG_DIRECT_TERM;
  // Otherwise, for the sun with no debug view, the build settles every pixel without a node and the
  // resolve reads only the others.
  const bool listed_resolve = !direct_term && debug_code(debug) == 0 && !spot;
  if (listed_resolve) flags |= gpu_shared::IZB_FLAG_LISTED_RESOLVE;
  if (hybrid) flags |= gpu_shared::IZB_FLAG_HYBRID;
  if (spot) flags |= gpu_shared::IZB_FLAG_SPOT;
  if (use_compute_trace) flags |= gpu_shared::IZB_FLAG_TILE_FARTHEST;
  // Every camera ray's points share their w where the inverse view-projection's w row ignores x and y
  // (exactly: then its products with them add zeros), so the μQuad corners take 1 / w from here.
  const glm::mat4& inverse_vp = frame.view.inverse_view_projection;
  const bool constant_ray_w = inverse_vp[0][3] == 0.0f && inverse_vp[1][3] == 0.0f;
  if (constant_ray_w) flags |= gpu_shared::IZB_FLAG_CONSTANT_RAY_W;
  // 32 spp and the sun: the fit bounds each μQuad from fast corners (izb_pixel.glsl, bound_micro_quad).
  const bool bounded_fit = constant_ray_w && m.samples == 32 && !spot;
  if (bounded_fit) flags |= gpu_shared::IZB_FLAG_BOUNDED_FIT;
  // 32 spp and the compute trace: a node per 2x2 block of texels a pixel's samples fill (izb.h).
  if (m.samples == 32 && use_compute_trace && settings.anchored_nodes) flags |= gpu_shared::IZB_FLAG_ANCHORED_NODES;
  m.ensure_resolve_list(frame.view.extent, listed_resolve);
  m.p = &m.pipelines(m.samples, flags);  // specialized for every flag above
  gpu_shared::IzbParams p{};
  p.light_view = light_view;
  p.inverse_view_projection = frame.view.inverse_view_projection;
  p.light_direction = glm::vec4(frame.view.light_direction, 0.0f);
  p.camera_position = glm::vec4(frame.view.camera_position, settings.max_distance);
  p.depth_range = glm::vec4(near_d, far_d, 0.0f, 0.0f);
  p.extent = glm::uvec4(frame.view.extent.width, frame.view.extent.height, settings.resolution, m.samples);
  p.limits = glm::uvec4(uint32_t(std::min<uint64_t>(m.pool_size, UINT32_MAX)), flags,
                        uint32_t(std::min<uint64_t>(m.records.capacity, UINT32_MAX)),
                        uint32_t(std::min<uint64_t>(m.pairs.capacity, UINT32_MAX)));
  p.capacities = glm::uvec4(uint32_t(std::min<uint64_t>(m.tile_pairs.capacity, UINT32_MAX)), m.tiles_per_side, m.caster_draws, step_one_shape);
  if (spot) {
    p.light_position = glm::vec4(frame.view.light_position, frame.view.light_range);
    p.light_cone = glm::vec4(frame.view.light_cos_outer, tan_half, frame.view.light_face ? 1.0f : 0.0f, 0.0f);
  }
  if (constant_ray_w) {
    // The same arithmetic as camera_ray at any pixel corner (pixel_corner_points' x and y terms are zeros).
    const gpu_shared::HomogeneousRay h = gpu_shared::pixel_corner_points(glm::vec2(0.0f), glm::vec2(1.0f), inverse_vp);
    p.ray_scales = glm::vec4(gpu_shared::shared_divide(1.0f, h.near_point.w),
                             gpu_shared::shared_divide(1.0f, h.far_point.w), 0.0f, 0.0f);
  }
  if (bounded_fit) set_corner_rays(p, inverse_vp, frame.view.extent);
  record_update(m.ctx, cmd, m.params, &p, sizeof(p));
  const gpu_shared::IzbComputePush push{hybrid ? 1u : 0u, debug_code(debug), m.triangle_count, soft_distance};

  // Reset: counters, lists, farthest depths.
  vkCmdFillBuffer(cmd, m.counters.handle(), 0, VK_WHOLE_SIZE, 0);
  if (sorted) vkCmdFillBuffer(cmd, m.list_counts.handle(), 0, VK_WHOLE_SIZE, 0);
  else vkCmdFillBuffer(cmd, m.heads.handle(), 0, VK_WHOLE_SIZE, gpu_shared::kIzbEndOfList);
  vkCmdFillBuffer(cmd, m.farthest.handle(), 0, VK_WHOLE_SIZE, 0);
  pass_barrier(frame.ctx, cmd);
  {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "light_frustum");
    {
      // The last of its workgroups also fits the grid and (with many casters) lists the caster draws
      // whose bounds reach it; on a CPU device a dispatch of its own does (IZB_FLAG_CPU_DEVICE).
      OptionalGpuRegion step(settings.step_timings, m.ctx, frame.profiler, cmd, "light_frustum_fit");
      m.dispatch(cmd, frame, m.p->fit, push, fit_columns(frame.view.extent.width), fit_rows(frame.view.extent.height));
    }
    if (cpu) {
      pass_barrier(frame.ctx, cmd);
      OptionalGpuRegion step(settings.step_timings, m.ctx, frame.profiler, cmd, "light_frustum_cull");
      m.dispatch(cmd, frame, m.p->setup, push, 1);
    }
    // The triangles into grid space, listed where they reach it: those of the listed draws, or with
    // few casters every one (where nothing before the compute trace reads them, in its step 1).
    if (!triangles_in_trace) {
      pass_barrier(frame.ctx, cmd);
      OptionalGpuRegion step(settings.step_timings, m.ctx, frame.profiler, cmd, "light_frustum_triangles");
      if (all_triangles) {
        const uint32_t groups = (m.triangle_count + 63) / 64;
        if (groups > 0) m.dispatch(cmd, frame, m.p->grid_setup, push, groups);
      } else {
        m.dispatch_indirect(cmd, frame, m.p->grid_setup, push, gpu_shared::IZB_COUNTER_GRID_SETUP_DISPATCH);
      }
    }
  }
  pass_barrier(frame.ctx, cmd);
  const VkDeviceSize grid_bytes = VkDeviceSize(m.resolution) * m.resolution * 4;
  if (lit) {
    // The lit map: every caster triangle's nearest depth over the texels it touches, binned over
    // light-space tiles like the compute CSM (it shares the CSM's work lists; the barrier below
    // orders the two). The build reads it.
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "lit_map");
    vkCmdFillBuffer(cmd, m.csm_texels.handle(), grid_bytes, VK_WHOLE_SIZE, gpu_shared::kIzbLitEmpty);
    pass_barrier(frame.ctx, cmd);
    m.record_tile_work(cmd, frame, push, gpu_shared::IZB_WORK_LIT, "lit", settings.step_timings);
    pass_barrier(frame.ctx, cmd);
  }
  if (run_csm) {
    if (use_compute_csm) {
      const uint32_t mode = settings.csm_test == CsmTest::Hertel ? gpu_shared::IZB_WORK_CSM_HERTEL
                                                                 : gpu_shared::IZB_WORK_CSM_BARYCENTRIC;
      m.csm->record(
          frame, settings, m.frame_data, m.resolution, collect_stats,
          [&](VkCommandBuffer c) {
            vkCmdFillBuffer(c, m.csm_texels.handle(), 0, grid_bytes, 0x3f800000u);  // 1.0: nothing stored
            pass_barrier(frame.ctx, c);
            m.record_tile_work(c, frame, push, mode, "csm", settings.step_timings);
          },
          &m.csm_texels);
    } else {
      m.csm->record(frame, settings, m.frame_data, m.resolution, collect_stats);
    }
    pass_barrier(frame.ctx, cmd);
  }
  {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "izb_build");
    {
      OptionalGpuRegion step(settings.step_timings, m.ctx, frame.profiler, cmd, "build_classify");
      m.dispatch_pixels(cmd, frame, m.p->build, push);
    }
    if (sorted) {
      // Counting sort: counts (above) -> prefix sum -> scatter into contiguous ranges.
      const uint32_t blocks = m.scan_blocks;
      for (uint32_t step = 0; step < 3; ++step) {
        pass_barrier(frame.ctx, cmd);
        gpu_shared::IzbComputePush scan_push = push;
        scan_push.mode = step;
        const uint32_t rows = (blocks + gpu_shared::kIzbDispatchRow - 1) / gpu_shared::kIzbDispatchRow;
        if (step == 1) m.dispatch(cmd, frame, m.p->scan, scan_push, 1);
        else m.dispatch(cmd, frame, m.p->scan, scan_push, std::min(blocks, gpu_shared::kIzbDispatchRow), rows);
      }
      pass_barrier(frame.ctx, cmd);
      m.dispatch_pixels(cmd, frame, m.p->scatter, push);
    }
    pass_barrier(frame.ctx, cmd);
    // A CPU device sizes the lists' dispatches in a pass of their own (izb_list_dispatch.comp), then
    // inserts the listed pixels' nodes where the build runs in two steps.
    if (listed_resolve && cpu) {
      OptionalGpuRegion step(settings.step_timings, m.ctx, frame.profiler, cmd, "build_insert");
      m.size_list_dispatch(cmd, frame, push, gpu_shared::IZB_LIST_RESOLVE);
      if (m.p->build_insert.valid()) {
        m.dispatch_indirect(cmd, frame, m.p->build_insert, push, gpu_shared::IZB_COUNTER_RESOLVE_LIST + 1);
        pass_barrier(frame.ctx, cmd);
      }
    }
  }
  // Light-space box around every point that can hold a node (the view, up to the IZB's range,
  // within the scene): a caster wholly beside it shadows none of them.
  const glm::mat4 receiver_region = [&] {
    const float reach = settings.max_distance > 0.0f ? std::min(settings.max_distance, frame.view.far_plane)
                                                     : frame.view.far_plane;
    glm::vec3 corners[8];
    view_slice_corners(frame.view, frame.view.near_plane, reach, corners);
    Aabb box;
    for (const glm::vec3& c : corners) box.extend(c);
    const Aabb scene = scene_bounds(frame);
    if (scene.valid()) box = {glm::max(box.min, scene.min), glm::min(box.max, scene.max)};
    if (!box.valid()) return glm::mat4(0.0f);  // nothing to receive: every caster culled
    // The shadow-ray offset and rounding may carry a node slightly outside.
    // fit_orthographic gives the projection alone: the clip matrix is it after the light's view.
    return fit_orthographic(light_view, box, 1e-3f * glm::length(box.extent()) + 1e-3f) * light_view;
  }();
  // The raster trace draws the opaque casters with pipelines whose node test has no alpha-test code
  // (a CPU device runs both sides of a branch), then the alpha-tested ones with it.
  const bool alpha = (flags & gpu_shared::IZB_FLAG_ALPHA) != 0;
  const Impl::TracePipelines& opaque_trace = alpha ? m.opaque_trace_pipelines(m.samples, flags) : m.p->trace;
  auto draw_trace = [&](bool count_only, VkCompareOp compare, bool fill_depth) {
    if (fill_depth) {
      // Each texel's farthest node depth becomes the depth the early test compares against (0 for an
      // empty texel: nothing passes). The build keeps them in [0,1], where float order is bit order,
      // so the buffer copies as it is; a full-screen depth-writing draw costs a CPU driver far more.
      VkBufferImageCopy region{};
      region.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
      region.imageExtent = {m.resolution, m.resolution, 1};
      vkCmdCopyBufferToImage(cmd, m.farthest.handle(), m.trace_depth.handle(), VK_IMAGE_LAYOUT_GENERAL, 1, &region);
      pass_barrier(frame.ctx, cmd);
    }
    begin_depth_rendering(cmd, m.trace_depth.view(), {m.resolution, m.resolution}, false);
    for (const CasterSet set : {alpha ? CasterSet::Opaque : CasterSet::All, CasterSet::AlphaTested}) {
      if (set == CasterSet::AlphaTested && !alpha) break;
      const Impl::TracePipelines& tp = set == CasterSet::AlphaTested ? m.p->trace : opaque_trace;
      const Pipeline& trace = count_only ? (use_hardware ? tp.count_hardware : tp.count_software)
                                         : (use_hardware ? tp.hardware : tp.software);
      trace.bind(cmd);
      vkCmdSetDepthBias(cmd, -1.0f, 0.0f, -1.0f);
      vkCmdSetDepthCompareOp(cmd, compare);
      m.push_all(cmd, frame, trace);
      draw_casters(
          cmd, frame,
          [&](const DrawItem& d, const MeshRange& range) {
            gpu_shared::IzbDrawPush dp{d.world, range.first_index, range.vertex_offset,
                                       m.first_triangle[size_t(&d - frame.draws.data())], 0u};
            trace.push_constants(cmd, dp);
          },
          set,
          // Rasterizing a caster costs a CPU driver per triangle even where it covers no node.
          [&](const DrawItem& d) { return d.bounds.outside_clip(receiver_region); });
    }
    vkCmdEndRendering(cmd);
  };
  if (use_compute_trace) {
    // Tiles' farthest nodes -> (triangle, tile) pairs not culled -> (triangle, texel) pairs that touch
    // and survive the texel's cull -> one thread per pair walks the texel's list.
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "frustum_trace");
    m.record_tile_work(cmd, frame, push, gpu_shared::IZB_WORK_TRACE, "trace", settings.step_timings);
    pass_barrier(frame.ctx, cmd);
    OptionalGpuRegion step(settings.step_timings, m.ctx, frame.profiler, cmd, "trace_pairs");
    m.dispatch_indirect(cmd, frame, m.p->trace_compute, push, gpu_shared::IZB_COUNTER_PAIR_DISPATCH);
  } else {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "frustum_trace");
    draw_trace(false, settings.depth_cull ? VK_COMPARE_OP_LESS : VK_COMPARE_OP_ALWAYS, true);
  }
  pass_barrier(frame.ctx, cmd);
  // With a node per pixel in a pool of one per pixel (IZB_FLAG_DIRECT_NODES) no pixel overflows.
  if ((flags & gpu_shared::IZB_FLAG_DIRECT_NODES) == 0) {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "izb_fallback");
    m.dispatch_indirect(cmd, frame, m.p->fallback, push, gpu_shared::IZB_COUNTER_DISPATCH);
    pass_barrier(frame.ctx, cmd);
  }
  if (!direct_term) {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "izb_resolve");
    const Pipeline& resolve = m.resolve_pipeline(m.samples, flags, debug_code(debug), hybrid);
    if (listed_resolve) m.dispatch_indirect(cmd, frame, resolve, push, gpu_shared::IZB_COUNTER_RESOLVE_LIST + 1);
    else m.dispatch_pixels(cmd, frame, resolve, push);
    pass_barrier(frame.ctx, cmd);
    if (hybrid && cpu) m.size_list_dispatch(cmd, frame, push, gpu_shared::IZB_LIST_HYBRID);
  }
  if (collect_stats) {
    // Statistics only (excluded from the technique's total): fragments before depth culling.
    // (The compute trace counts fragments before the cull as it bins.)
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "izb_stats");
    if (!use_compute_trace) {
      draw_trace(true, VK_COMPARE_OP_ALWAYS, false);
      pass_barrier(frame.ctx, cmd);
    }
    m.dispatch(cmd, frame, m.p->list_stats, push, (m.resolution + 7) / 8, (m.resolution + 7) / 8);
  }
  m.counters_readback.record_copy(frame, m.counters, m.counters.size(),
                                  pass_shader_stages(m.ctx) | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                                  VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                  "izb counters readback");
}

engine::gpu::Image& IzbPass::soft_term() { return impl_->soft_term; }

PixelList IzbPass::hybrid_list() const {
  return {impl_->hybrid_list.handle(), impl_->counters.handle(), gpu_shared::IZB_COUNTER_HYBRID};
}

void IzbPass::record_hybrid_blend(Frame& frame) {
  Impl& m = *impl_;
  VkCommandBuffer cmd = frame.cmd;
  if (!m.hybrid_blend.valid())
    m.hybrid_blend = m.factory.compute({"izb_hybrid_blend.comp", izb_bindings(), sizeof(gpu_shared::IzbComputePush)});
  ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "hybrid_blend");
  m.hybrid_blend.bind(cmd);
  m.push_all(cmd, frame, m.hybrid_blend);
  vkCmdDispatchIndirect(cmd, m.counters.handle(), (gpu_shared::IZB_COUNTER_HYBRID + 1) * 4);
}

CsmSnapshot IzbPass::read_csm() {
  Impl& m = *impl_;
  CsmSnapshot snapshot;
  if (!m.last_used_csm) return snapshot;
  snapshot.resolution = m.resolution;
  if (m.used_compute_csm) {
    const auto bytes = read_buffer(m.ctx, m.csm_texels);
    snapshot.depth.resize(size_t(m.resolution) * m.resolution);
    std::memcpy(snapshot.depth.data(), bytes.data(), snapshot.depth.size() * sizeof(float));
  } else {
    snapshot.depth = m.csm->read_depth();
  }
  const auto frame_bytes = read_buffer(m.ctx, m.frame_data);
  gpu_shared::IzbFrame frame;
  std::memcpy(&frame, frame_bytes.data(), sizeof(frame));
  snapshot.light_view_projection = frame.light_view_projection;
  return snapshot;
}

LitMapSnapshot IzbPass::read_lit_map() {
  Impl& m = *impl_;
  LitMapSnapshot snapshot;
  if (!m.last_used_lit) return snapshot;
  snapshot.resolution = m.resolution;
  const auto bytes = read_buffer(m.ctx, m.csm_texels);
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
  const size_t texels = size_t(m.resolution) * m.resolution;
  snapshot.depth = decode(texels, texels);
  const size_t corners = size_t(m.resolution + 1) * (m.resolution + 1);
  snapshot.corner_depth = decode(2 * texels, corners);
  snapshot.tile = gpu_shared::kIzbTile;
  snapshot.tiles_per_side = m.tiles_per_side;
  const size_t tiles = size_t(m.tiles_per_side) * m.tiles_per_side;
  // Each tile's record (izb_common.glsl, lit_tile_record): least texel bound, bound, c00, c10, c01, c11.
  const std::vector<float> records = decode(gpu_shared::izb_lit_tile_records_at(m.resolution), 8 * tiles);
  for (size_t t = 0; t < tiles; ++t) {
    snapshot.tile_least_depth.push_back(records[8 * t]);
    snapshot.tile_depth.push_back(records[8 * t + 1]);
    snapshot.tile_corner_depth.insert(snapshot.tile_corner_depth.end(), records.begin() + 8 * t + 2, records.begin() + 8 * t + 6);
  }
  const auto frame_bytes = read_buffer(m.ctx, m.frame_data);
  gpu_shared::IzbFrame frame;
  std::memcpy(&frame, frame_bytes.data(), sizeof(frame));
  snapshot.light_view_projection = frame.light_view_projection;
  return snapshot;
}

void IzbPass::after_frame(std::vector<Stats>& records, uint32_t slot) {
  Impl& m = *impl_;
  m.csm->frame_completed(slot);
  const auto readbacks = m.counters_readback.take_all(slot);
  if (readbacks.empty()) return;
  // The work lists and the pool grow to the most any record of the frame asked for.
  uint64_t records_asked = 0, tile_pairs_asked = 0, pairs_asked = 0, nodes_asked = 0;
  for (const Buffer* readback : readbacks) {
    const auto* c = readback->as<uint32_t>();
    auto sharded = [&](uint32_t counter) {
      uint64_t sum = 0;
      for (uint32_t k = 0; k < gpu_shared::kIzbCounterShards; ++k)
        sum += c[gpu_shared::IZB_COUNTER_SHARDS + counter * gpu_shared::kIzbCounterShards + k];
      return sum;
    };
    Stats& s = records.emplace_back();
    s.shading_points = sharded(gpu_shared::IZB_COUNTER_SHADING_POINTS);
    s.lit_candidates = sharded(gpu_shared::IZB_COUNTER_CANDIDATES);
    const uint64_t requested = c[gpu_shared::IZB_COUNTER_NODES];
    s.node_pool_size = m.pool_size;
    s.nodes_inserted = std::min<uint64_t>(requested, m.pool_size);
    s.node_overflow = c[gpu_shared::IZB_COUNTER_OVERFLOW];
    s.overflow_pixels = c[gpu_shared::IZB_COUNTER_OVERFLOW_PIXELS];
    s.csm_culled = sharded(gpu_shared::IZB_COUNTER_CSM_CULLED);
    s.culling_rate = s.lit_candidates ? double(s.csm_culled) / double(s.lit_candidates) : 0.0;
    s.lit_culled = sharded(gpu_shared::IZB_COUNTER_LIT_CULLED);
    s.caster_triangles = m.triangle_count;
    s.caster_triangles_listed = c[gpu_shared::IZB_COUNTER_LISTED_TRIANGLES];
    s.trace_fragments_before_cull = sharded(gpu_shared::IZB_COUNTER_FRAGMENTS);
    s.trace_fragments_after_cull = sharded(gpu_shared::IZB_COUNTER_FRAGMENTS_KEPT);
    s.triangle_tests = sharded(gpu_shared::IZB_COUNTER_TRIANGLE_TESTS);
    s.triangle_tests_per_pixel = s.lit_candidates ? double(s.triangle_tests) / double(s.lit_candidates) : 0.0;
    s.list_length_max = c[gpu_shared::IZB_COUNTER_LIST_MAX];
    s.nonempty_texels = c[gpu_shared::IZB_COUNTER_NONEMPTY];
    s.list_length_average =
        s.nonempty_texels ? double(c[gpu_shared::IZB_COUNTER_LIST_SUM]) / double(s.nonempty_texels) : 0.0;
    s.hardware_conservative = m.used_hardware;
    s.trace_choice = m.trace_probe.choice();
    if (m.last_used_csm) s.csm_choice = m.csm_probe.choice();
    s.lit_choice = m.lit_probe.choice();
    s.csm_run_choice = m.csm_run_probe.choice();
    s.tile_work_choice = m.shape_probe.choice();
    if (m.used_compute_trace) {
      s.trace_records = c[gpu_shared::IZB_COUNTER_RECORDS];
      s.trace_tile_pairs = c[gpu_shared::IZB_COUNTER_TILE_PAIRS];
      s.trace_pairs = c[gpu_shared::IZB_COUNTER_PAIRS];
    }
    records_asked = std::max({records_asked, uint64_t(c[gpu_shared::IZB_COUNTER_RECORDS]),
                              uint64_t(c[gpu_shared::IZB_COUNTER_RECORDS + 1]), uint64_t(c[gpu_shared::IZB_COUNTER_LIT_RECORDS])});
    tile_pairs_asked = std::max({tile_pairs_asked, uint64_t(c[gpu_shared::IZB_COUNTER_TILE_PAIRS]),
                                 uint64_t(c[gpu_shared::IZB_COUNTER_TILE_PAIRS + 1]),
                                 uint64_t(c[gpu_shared::IZB_COUNTER_LIT_TILE_PAIRS])});
    pairs_asked = std::max<uint64_t>(pairs_asked, c[gpu_shared::IZB_COUNTER_PAIRS]);
    nodes_asked = std::max(nodes_asked, requested);
  }
  // Grow the compute passes' work lists to what this frame asked for (trace, CSM or lit map, whichever
  // more).
  auto grow = [](Impl::WorkList& list, uint64_t asked) {
    if (asked > list.capacity) list.demand = uint64_t(double(asked) * 1.25);
  };
  const bool overflowed = records_asked > m.records.capacity || tile_pairs_asked > m.tile_pairs.capacity ||
                          pairs_asked > m.pairs.capacity || nodes_asked > m.pool_size;
  if (overflowed) {  // a frame slowed by an overflow does not speak for its backend
    m.trace_probe.discard_pending(slot);
    m.csm_probe.discard_pending(slot);
    m.lit_probe.discard_pending(slot);
    m.csm_run_probe.discard_pending(slot);
    m.shape_probe.discard_pending(slot);
  }
  grow(m.records, records_asked);
  grow(m.tile_pairs, tile_pairs_asked);
  grow(m.pairs, pairs_asked);
  Stats& last = records.back();
  for (uint32_t k = 0; k < records.size(); ++k) m.csm->note_yield(slot, k, records[k].culling_rate);
  m.csm->after_frame(last, slot);
  // Grow the pool for the next frame when this one overflowed (unless a fixed size was asked for).
  if (nodes_asked > m.pool_size) m.pool_demand = uint64_t(double(nodes_asked) * 1.25);
}

uint32_t IzbPass::records_so_far(uint32_t slot, uint64_t frame_index) const {
  return impl_->counters_readback.recorded(slot, frame_index);
}

}  // namespace shadows::detail
