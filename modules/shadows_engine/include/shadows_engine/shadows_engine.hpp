#pragma once
// The shadow module inside this repository's engine: installed into an engine::Renderer as a
// RenderFeature that hands the renderer's G-buffer, meshes and draws to shadows::Context (the host
// API of shadows/context.hpp, which other engines use directly).
//
//   auto shadows = shadows::install(renderer, shadows::Settings{});
//   shadows->settings().technique = shadows::Technique::Izb;
//   ... after a frame: shadows->stats().nodes_inserted
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/render/renderer.hpp"
#include "shadows/shadows.hpp"

namespace shadows {

class ShadowModule : public engine::RenderFeature {
 public:
  virtual Settings& settings() = 0;
  // Statistics of the last completed frame (the renderer waits for each frame, so: the last frame).
  virtual const Stats& stats() const = 0;
  // Statistics are read back every frame only while enabled (costs a small readback); the automatic
  // choices in them follow every frame either way.
  virtual void set_collect_stats(bool enabled) = 0;
  // Names of the GPU passes the current settings can record, in order (profiler region names; a pass a
  // frame did not run, such as the local-light maps of cascades under the sun alone, has no region).
  virtual std::vector<std::string> pass_names() const = 0;
  // Whether a coverage test / technique can run on this device, and why not.
  virtual bool supported(CsmTest test, std::string* why = nullptr) const = 0;
  virtual bool supported(Technique technique, std::string* why = nullptr) const = 0;
  // Per-pixel visibility of the last frame (1 lit .. 0 shadowed, -1 background), for tests/tools.
  virtual std::vector<float> read_visibility() = 0;
  // The last frame's conservative shadow map (row-major, resolution^2 depths, 1 = nothing stored) and
  // the GPU-fitted world -> light clip transform it was rendered with. Empty when the CSM did not run.
  struct CsmSnapshot {
    uint32_t resolution = 0;
    std::vector<float> depth;
    glm::mat4 light_view_projection{1.0f};
    std::vector<float> corner_depth;  // the lit map's alone: its texel corners' plane bounds, (resolution + 1)^2
    // The lit map's alone, its tile level: casters that cover a whole tile of `tile`^2 texels are
    // bounded there instead (a bound per tile, tiles_per_side^2, row-major, and each tile's own four
    // corners' plane bounds, c00, c10, c01, c11, 4 * tiles_per_side^2; corner i at min(i * tile,
    // resolution)).
    uint32_t tile = 0, tiles_per_side = 0;
    std::vector<float> tile_depth, tile_corner_depth;
    // The lit map's alone: per tile, no farther than any of its texels' `depth` (tiles_per_side^2).
    std::vector<float> tile_least_depth;
  };
  virtual CsmSnapshot read_csm() = 0;
  // The last frame's lit map (IzbSettings::lit_culling; row-major, resolution^2 depths, +infinity
  // where no caster touches the texel; the corners' plane bounds; the tile level) and the transform
  // it was built with. Empty when it did not run.
  virtual CsmSnapshot read_lit_map() = 0;
  // The host-API context the adapter drives.
  virtual Context& context() = 0;
  // The one light the module shadows from the next frame on, into the renderer's sun term, instead of
  // the renderer's sun and local lights (nullopt: those again). A local light's position is in scene
  // space, as its Transform places it (relative to engine::Scene::origin). The renderer's lighting is
  // not told: for tests and tools that read the visibility.
  virtual void set_light(std::optional<Light> light) = 0;
  // From the next frame on, hands the renderer's G-buffer over as any other engine would (depth,
  // normals, geometric normals with the light-facing decision, terminator offset, receiver mask), so
  // the module's input pass rebuilds the shading points, instead of as native shading points read in
  // place (the default). The visibility is the same bit for bit; for tests of the host path. The
  // environment variable ENGINE_HOST_INPUTS=1 makes `true` the starting value of every module.
  virtual void set_host_inputs(bool enabled) = 0;
};

// Creates the module on the renderer's device, adds it to the renderer, and returns it. Each frame it
// records the module's passes into the renderer's terms, except with Technique::Off and no debug
// view: then it records nothing (no `shadows` profiler region, stats() as the last recorded frame
// left them) and the renderer keeps the terms lit.
std::shared_ptr<ShadowModule> install(engine::Renderer& renderer, const Settings& settings = {});

// The module's description of one of the renderer's local lights (FrameView::local_lights).
Light light_of(const engine::FrameLight& light);

// The entity a CSM decision is about (the adapter's Instance::id is index << 32 | generation).
inline engine::Entity entity_of(const CsmDecision& decision) {
  return engine::Entity{uint32_t(decision.instance_id >> 32), uint32_t(decision.instance_id & 0xffffffffu)};
}
inline uint64_t instance_id_of(engine::Entity entity) { return (uint64_t(entity.index) << 32) | entity.generation; }

}  // namespace shadows
