#include <stdexcept>

#include "engine/gpu/profiler.hpp"
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

  std::vector<std::string> pass_names() const override {
    switch (settings_.technique) {
      case Technique::Off: return {};
      case Technique::ShadowMap: return {"sm_depth", "sm_resolve"};
      default: return {};
    }
  }

  bool supported(CsmTest, std::string* why) const override {
    if (why) *why = "not implemented";
    return false;
  }

  void record(engine::FrameContext& frame) override {
    engine::gpu::ScopedGpuRegion region(ctx_, frame.profiler, frame.cmd, "shadows");
    switch (settings_.technique) {
      case Technique::Off:
        break;
      case Technique::ShadowMap:
        if (!shadow_map_) shadow_map_ = std::make_unique<ShadowMapPass>(ctx_);
        shadow_map_->record(frame, settings_.shadow_map);
        break;
      default:
        throw std::runtime_error("shadow technique not available yet");
    }
  }

  std::vector<float> read_visibility() override {
    auto term = renderer_.read_shadow_term();
    const auto positions = renderer_.read_world_positions();
    for (size_t i = 0; i < term.size(); ++i)
      if (positions[i].w == 0.0f) term[i] = -1.0f;
    return term;
  }

 private:
  engine::Renderer& renderer_;
  engine::gpu::Context& ctx_;
  Settings settings_;
  Stats stats_;
  bool collect_stats_ = true;
  std::unique_ptr<ShadowMapPass> shadow_map_;
};

}  // namespace detail

std::shared_ptr<ShadowModule> install(engine::Renderer& renderer, const Settings& settings) {
  auto module = std::make_shared<detail::ShadowModuleImpl>(renderer, settings);
  renderer.add_feature(module);
  return module;
}

}  // namespace shadows
