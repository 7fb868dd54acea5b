#include "izb_pipelines.hpp"

#include "barriers.hpp"

#include "shared/izb.h"

namespace shadows::detail {

using namespace engine::gpu;

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

bool IzbPipelineCache::hardware_trace_available() const {
  return ctx_.features().conservative_rasterization && ctx_.features().geometry_shader;
}
bool IzbPipelineCache::raster_trace_available() const { return ctx_.features().geometry_shader; }
bool IzbPipelineCache::cpu_device() const { return cpu_paths_; }

std::vector<SpecializationConstant> IzbPipelineCache::with_pixel_group(std::vector<SpecializationConstant> constants) const {
  return detail::with_pixel_group(std::move(constants), 20, cpu_paths_);
}

std::vector<SpecializationConstant> IzbPipelineCache::fit_group(uint32_t samples_per_pixel, uint32_t flags) const {
  const bool rows = cpu_paths_ && (samples_per_pixel == 1 || (flags & gpu_shared::IZB_FLAG_BOUNDED_FIT));
  return {{20, rows ? 32u : 16u}, {21, rows ? 8u : 16u}};
}

IzbPipelines& IzbPipelineCache::set(uint32_t samples_per_pixel, uint32_t flags) {
  auto& slot = sets_[(uint64_t(samples_per_pixel) << 32) | flags];
  if (slot) return *slot;
  slot = std::make_unique<IzbPipelines>();
  IzbPipelines& ps = *slot;
  const auto bindings = izb_bindings();
  const uint32_t push = sizeof(gpu_shared::IzbComputePush);
  const std::vector<SpecializationConstant> variant = {{10, samples_per_pixel}, {11, flags}};
  auto compute = [&](const char* shader, std::vector<SpecializationConstant> constants = {}) {
    constants.insert(constants.end(), variant.begin(), variant.end());
    return factory_.compute({shader, bindings, push, constants});
  };
  ps.fit = compute("izb_fit.comp", fit_group(samples_per_pixel, flags));
  if (flags & gpu_shared::IZB_FLAG_CPU_DEVICE) {
    ps.setup = compute("izb_setup.comp");
    ps.list_dispatch = compute("izb_list_dispatch.comp");
  }
  // A CPU device with one node a pixel and a listed resolve: the build classifies every pixel, then
  // inserts the listed ones' nodes in a dispatch over the list (izb_build.comp, kBuildStep).
  const bool build_apart = (flags & gpu_shared::IZB_FLAG_CPU_DEVICE) && (flags & gpu_shared::IZB_FLAG_DIRECT_NODES) &&
                           (flags & gpu_shared::IZB_FLAG_LISTED_RESOLVE);
  ps.build = compute("izb_build.comp", with_pixel_group({{14, build_apart ? 1u : 0u}}));
  if (build_apart) ps.build_insert = compute("izb_build.comp", with_pixel_group({{14, 2u}}));
  if (flags & gpu_shared::IZB_FLAG_FACE_TILES) ps.face_tiles = compute("izb_face_tiles.comp");
  ps.fallback = compute("izb_fallback.comp");
  ps.list_stats = compute("izb_list_stats.comp");
  ps.grid_setup = compute("izb_triangles.comp");
  ps.scan = compute("izb_scan.comp");
  ps.scatter = compute("izb_scatter.comp", with_pixel_group({}));
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

const IzbTracePipelines& IzbPipelineCache::opaque_trace(uint32_t samples_per_pixel, uint32_t flags) {
  auto [it, fresh] = opaque_traces_.try_emplace((uint64_t(samples_per_pixel) << 32) | flags);
  if (fresh) it->second = trace_pipelines(samples_per_pixel, flags & ~gpu_shared::IZB_FLAG_ALPHA);
  return it->second;
}

IzbTracePipelines IzbPipelineCache::trace_pipelines(uint32_t samples_per_pixel, uint32_t flags) {
  IzbTracePipelines tp;
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
    return factory_.graphics(trace);
  };
  if (ctx_.features().geometry_shader) {
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

const Pipeline& IzbPipelineCache::resolve(uint32_t samples_per_pixel, uint32_t flags, uint32_t debug, bool hybrid) {
  auto& pipeline = resolve_pipelines_[(uint64_t(samples_per_pixel) << 40) | (uint64_t(debug) << 33) |
                                      (uint64_t(hybrid) << 32) | flags];
  if (!pipeline.valid())
    pipeline = factory_.compute(
        {"izb_resolve.comp", izb_bindings(), sizeof(gpu_shared::IzbComputePush),
         with_pixel_group({{10, samples_per_pixel}, {11, flags}, {12, debug}, {13, hybrid ? 1u : 0u}})});
  return pipeline;
}

const IzbPipelines::TileWork& IzbPipelineCache::tile_work(IzbPipelines& set, uint32_t mode) {
  IzbPipelines::TileWork& w = set.tile_work.at(mode);
  if (w.records.valid()) return w;
  std::vector<SpecializationConstant> constants = set.constants;
  constants.push_back({5, mode});
  const auto bindings = izb_bindings();
  const uint32_t push = sizeof(gpu_shared::IzbComputePush);
  w.records = factory_.compute({"izb_records.comp", bindings, push, constants});
  w.tile_bin = factory_.compute({"izb_tile_bin.comp", bindings, push, constants});
  w.texel_bin = factory_.compute({"izb_texel_bin.comp", bindings, push, constants});
  return w;
}

const Pipeline& IzbPipelineCache::build_casters() {
  if (!build_casters_.valid())
    build_casters_ = factory_.compute({"izb_casters.comp",
                                       {{gpu_shared::IZB_CASTERS_BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                        {gpu_shared::IZB_CASTERS_BINDING_INDICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                        {gpu_shared::IZB_CASTERS_BINDING_DRAWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                        {gpu_shared::IZB_CASTERS_BINDING_TRIANGLES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
                                       sizeof(gpu_shared::IzbCastersPush)});
  return build_casters_;
}

const Pipeline& IzbPipelineCache::hybrid_blend() {
  if (!hybrid_blend_.valid())
    hybrid_blend_ = factory_.compute({"izb_hybrid_blend.comp", izb_bindings(), sizeof(gpu_shared::IzbComputePush)});
  return hybrid_blend_;
}

const Pipeline& IzbPipelineCache::penumbra(uint32_t step) {
  Pipeline& pipeline = penumbra_.at(step);
  if (!pipeline.valid())
    pipeline = factory_.compute({"izb_penumbra.comp", izb_bindings(), sizeof(gpu_shared::IzbComputePush),
                                 {{14, step}, {11, cpu_device() ? gpu_shared::IZB_FLAG_CPU_DEVICE : 0u}}});
  return pipeline;
}

}  // namespace shadows::detail
