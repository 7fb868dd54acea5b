#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "gpu/pipeline.hpp"

namespace shadows::detail {

// Every IZB pass binds the same set (izb.h's IZB_BINDING_*), so one layout serves them all.
std::vector<engine::gpu::Binding> izb_bindings();

// The raster trace: software (geometry-shader quads + exact texel test) and hardware conservative
// rasterization, each also as a count-only variant for the before-culling fragment statistic.
struct IzbTracePipelines {
  engine::gpu::Pipeline software, hardware, count_software, count_hardware;
};

// Every IZB pipeline, specialized for a sample count and a set of IZB_FLAG_* (see izb_common.glsl).
struct IzbPipelines {
  engine::gpu::Pipeline fit, setup, build, fallback, list_stats, grid_setup, scan, scatter, list_dispatch;
  engine::gpu::Pipeline build_insert;  // valid where the build runs in two steps (izb_build.comp, kBuildStep)
  engine::gpu::Pipeline face_tiles;    // valid with IZB_FLAG_FACE_TILES (izb_face_tiles.comp)
  // Steps 1-3 of the tile work, per work (IZB_WORK_*), made on first use (IzbPipelineCache::tile_work)
  // with the set's constants.
  struct TileWork {
    engine::gpu::Pipeline records, tile_bin, texel_bin;
  };
  std::array<TileWork, 4> tile_work;
  std::vector<engine::gpu::SpecializationConstant> constants;  // the compute trace's workgroup shape, samples, flags
  engine::gpu::Pipeline trace_compute;
  IzbTracePipelines trace;
};

// Makes the IZB's pipelines on first use and keeps them, per sample count and flags.
class IzbPipelineCache {
 public:
  // `cpu_paths`: the module's takes_cpu_paths, decided once when it was created.
  IzbPipelineCache(engine::gpu::Context& ctx, bool cpu_paths) : ctx_(ctx), cpu_paths_(cpu_paths), factory_(ctx) {}
  // The pipelines for `samples_per_pixel` and `flags`.
  IzbPipelines& set(uint32_t samples_per_pixel, uint32_t flags);
  // Opaque casters' raster trace where some are alpha-tested (without the alpha-test code).
  const IzbTracePipelines& opaque_trace(uint32_t samples_per_pixel, uint32_t flags);
  // The resolve, also per debug view and hybrid.
  const engine::gpu::Pipeline& resolve(uint32_t samples_per_pixel, uint32_t flags, uint32_t debug, bool hybrid);
  // `set`'s pipelines of steps 1-3 for `mode` (IZB_WORK_*).
  const IzbPipelines::TileWork& tile_work(IzbPipelines& set, uint32_t mode);
  const engine::gpu::Pipeline& build_casters();
  const engine::gpu::Pipeline& hybrid_blend();
  // The hybrid's penumbra pass, per step (izb_penumbra.comp's kStep*).
  const engine::gpu::Pipeline& penumbra(uint32_t step);

  // The trace's fragment shader reads gl_PrimitiveID, which SPIR-V puts under the Geometry capability:
  // the hardware conservative trace needs geometry shaders as much as the software one does.
  bool hardware_trace_available() const;
  bool raster_trace_available() const;
  // A CPU device (lavapipe) pays for every workgroup, idle lane and barrier: it takes other shapes.
  bool cpu_device() const;
  // The fit's workgroup of 256 (izb_fit.comp, specialization constants 20 and 21): 16x16, or on a CPU
  // device, where it makes no block of corner rays (1 spp, or IZB_FLAG_BOUNDED_FIT), 32x8, whose rows
  // lavapipe ran the fit about a third faster with.
  std::vector<engine::gpu::SpecializationConstant> fit_group(uint32_t samples_per_pixel, uint32_t flags) const;
  // `constants` and the per-pixel passes' workgroup (build, scatter, resolve: specialization constants
  // 20 and 21; barriers.hpp's pixel_group_width).
  std::vector<engine::gpu::SpecializationConstant> with_pixel_group(
      std::vector<engine::gpu::SpecializationConstant> constants) const;

 private:
  IzbTracePipelines trace_pipelines(uint32_t samples_per_pixel, uint32_t flags);

  engine::gpu::Context& ctx_;
  bool cpu_paths_;  // takes_cpu_paths
  engine::gpu::PipelineFactory factory_;
  std::map<uint64_t, std::unique_ptr<IzbPipelines>> sets_;
  std::map<uint64_t, engine::gpu::Pipeline> resolve_pipelines_;
  std::map<uint64_t, IzbTracePipelines> opaque_traces_;
  engine::gpu::Pipeline build_casters_;
  engine::gpu::Pipeline hybrid_blend_;
  std::array<engine::gpu::Pipeline, 4> penumbra_;
};

}  // namespace shadows::detail
