#include <cctype>
#include <stdexcept>

#include "cascades_pass.hpp"
#include "engine/gpu/profiler.hpp"
#include "izb_pass.hpp"
#include "ray_traced_pass.hpp"
#include "shadow_map_pass.hpp"
#include "shadows/shadows.hpp"

namespace shadows {

namespace detail {

class ShadowModuleImpl final : public ShadowModule {
 public:
  ShadowModuleImpl(engine::Renderer& renderer, const Settings& settings)
      : renderer_(renderer), ctx_(renderer.context()), settings_(settings) {}

  std::string name() const override { return "shadows"; }
  Settings& settings() override { return settings_; }
  const Stats& stats() const override { return stats_; }
  void set_collect_stats(bool enabled) override { collect_stats_ = enabled; }

  // The technique's own passes (statistics-only passes such as izb_stats and csm_coverage excluded).
  std::vector<std::string> pass_names() const override {
    std::vector<std::string> izb = {"light_frustum", "izb_build", "frustum_trace", "izb_fallback", "izb_resolve"};
    if (settings_.izb.csm) izb.insert(izb.begin() + 1, "csm");
    const std::vector<std::string> cascades = {"cascade_depth", "cascade_masks", "cascade_filter", "cascade_blur"};
    switch (settings_.technique) {
      case Technique::Off: return {};
      case Technique::ShadowMap: return {"sm_depth", "sm_resolve"};
      case Technique::Cascades: return cascades;
      case Technique::Izb: return izb;
      case Technique::Hybrid: {
        izb.insert(izb.begin(), cascades.begin(), cascades.end());
        return izb;
      }
      case Technique::RayTraced: return {"rt_build", "rt_trace"};
    }
    return {};
  }

  bool supported(CsmTest test, std::string* why) const override { return izb().csm_test_supported(test, why); }
  bool supported(Technique technique, std::string* why) const override {
    if (technique != Technique::RayTraced || ctx_.features().ray_tracing_pipeline) return true;
    if (why) *why = ctx_.features().ray_tracing_missing;
    return false;
  }

  void on_scene(engine::gpu::Context&, engine::Scene&, engine::SceneGeometry&) override {
    if (ray_traced_) ray_traced_->scene_changed();
  }

  void record(engine::FrameContext& frame) override {
    engine::gpu::ScopedGpuRegion region(ctx_, frame.profiler, frame.cmd, "shadows");
    active_ = settings_.technique;
    switch (settings_.technique) {
      case Technique::Off:
        break;
      case Technique::ShadowMap:
        if (!shadow_map_) shadow_map_ = std::make_unique<ShadowMapPass>(ctx_);
        shadow_map_->record(frame, settings_.shadow_map);
        break;
      case Technique::Cascades:
        cascades().record(frame, settings_.cascades, frame.shadow_term, settings_.debug);
        break;
      case Technique::Izb:
        izb().record(frame, settings_.izb, settings_.debug, false, collect_stats_);
        break;
      case Technique::Hybrid: {
        // IZB first: its resolve lists the pixels that take some of the cascades' term, and the
        // cascades filter only those.
        IzbSettings near = settings_.izb;
        near.max_distance = settings_.hybrid_izb_distance;
        izb().record(frame, near, settings_.debug, true, collect_stats_, settings_.hybrid_soft_distance);
        engine::gpu::full_barrier(frame.cmd);
        const PixelList listed = izb().hybrid_list();
        cascades().record(frame, settings_.cascades, izb().soft_term(), settings_.debug, &listed);
        engine::gpu::full_barrier(frame.cmd);
        izb().record_hybrid_blend(frame);
        break;
      }
      case Technique::RayTraced:
        // Throws the device's one-line reason where it cannot trace (supported() tells beforehand).
        if (!ray_traced_) ray_traced_ = std::make_unique<RayTracedPass>(ctx_);
        ray_traced_->record(frame, settings_.izb.samples_per_pixel, collect_stats_);
        break;
    }
  }

  void after_frame(engine::gpu::Context&) override {
    // Always: the passes grow their pools and buffers to the demand they measured.
    Stats fresh;  // only the techniques that ran this frame report
    if ((active_ == Technique::Izb || active_ == Technique::Hybrid) && izb_) izb_->after_frame(fresh);
    if ((active_ == Technique::Cascades || active_ == Technique::Hybrid) && cascades_) cascades_->after_frame(fresh);
    if (active_ == Technique::RayTraced && ray_traced_) ray_traced_->after_frame(fresh);
    if (collect_stats_) {
      add_memory(fresh);
      stats_ = std::move(fresh);
    }
  }

  std::vector<float> read_visibility() override {
    auto term = renderer_.read_shadow_term();
    const auto positions = renderer_.read_world_positions();
    for (size_t i = 0; i < term.size(); ++i)
      if (positions[i].w == 0.0f) term[i] = -1.0f;
    return term;
  }

  CsmSnapshot read_csm() override { return izb_ ? izb_->read_csm() : CsmSnapshot{}; }

 private:
  // The memory of the active technique's resources, found by the prefixes of their debug names.
  void add_memory(Stats& s) const {
    std::vector<std::string> prefixes;
    switch (active_) {
      case Technique::Off: break;
      case Technique::ShadowMap: prefixes = {"sm "}; break;
      case Technique::Cascades: prefixes = {"cascade "}; break;
      case Technique::Izb: prefixes = {"izb "}; break;
      case Technique::Hybrid: prefixes = {"izb ", "cascade "}; break;
      case Technique::RayTraced: prefixes = {"rt "}; break;
    }
    if ((active_ == Technique::Izb || active_ == Technique::Hybrid) && settings_.izb.csm) prefixes.push_back("csm ");
    for (const auto& a : ctx_.allocations()) {
      // Staging and readback copies are transient or host-side; they are not the technique's memory.
      if (a.name.find("staging") != std::string::npos || a.name.find("readback") != std::string::npos) continue;
      for (const auto& prefix : prefixes) {
        if (a.name.compare(0, prefix.size(), prefix) != 0) continue;
        // Numbered resources (one bottom level per mesh) add up under one name.
        std::string key = a.name;
        while (!key.empty() && (std::isdigit(static_cast<unsigned char>(key.back())) || key.back() == ' ')) key.pop_back();
        s.memory_bytes[key] += a.bytes;
        s.memory_total_bytes += a.bytes;
        break;
      }
    }
  }

  IzbPass& izb() const {
    if (!izb_) izb_ = std::make_unique<IzbPass>(ctx_);
    return *izb_;
  }
  CascadesPass& cascades() {
    if (!cascades_) cascades_ = std::make_unique<CascadesPass>(ctx_);
    return *cascades_;
  }

  engine::Renderer& renderer_;
  engine::gpu::Context& ctx_;
  Settings settings_;
  Stats stats_;
  Technique active_ = Technique::Off;
  bool collect_stats_ = true;
  std::unique_ptr<ShadowMapPass> shadow_map_;
  mutable std::unique_ptr<IzbPass> izb_;
  std::unique_ptr<CascadesPass> cascades_;
  std::unique_ptr<RayTracedPass> ray_traced_;
};

}  // namespace detail

std::shared_ptr<ShadowModule> install(engine::Renderer& renderer, const Settings& settings) {
  auto module = std::make_shared<detail::ShadowModuleImpl>(renderer, settings);
  renderer.add_feature(module);
  return module;
}

}  // namespace shadows
