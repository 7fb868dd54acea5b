#include <stdexcept>

#include "cascades_pass.hpp"
#include "engine/gpu/profiler.hpp"
#include "izb_pass.hpp"
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
    }
    return {};
  }

  bool supported(CsmTest test, std::string* why) const override { return izb().csm_test_supported(test, why); }

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
        cascades().record(frame, settings_.cascades, frame.shadow_term, settings_.debug);
        engine::gpu::full_barrier(frame.cmd);
        IzbSettings near = settings_.izb;
        near.max_distance = settings_.hybrid_izb_distance;
        izb().record(frame, near, settings_.debug, true, collect_stats_, settings_.hybrid_soft_distance);
        break;
      }
    }
  }

  void after_frame(engine::gpu::Context&) override {
    // Always: the passes grow their pools and buffers to the demand they measured.
    Stats fresh;  // only the techniques that ran this frame report
    if ((active_ == Technique::Izb || active_ == Technique::Hybrid) && izb_) izb_->after_frame(fresh);
    if ((active_ == Technique::Cascades || active_ == Technique::Hybrid) && cascades_) cascades_->after_frame(fresh);
    if (collect_stats_) stats_ = std::move(fresh);
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
};

}  // namespace detail

std::shared_ptr<ShadowModule> install(engine::Renderer& renderer, const Settings& settings) {
  auto module = std::make_shared<detail::ShadowModuleImpl>(renderer, settings);
  renderer.add_feature(module);
  return module;
}

}  // namespace shadows
