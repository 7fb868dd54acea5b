#pragma once
// The context behind shadows/context.hpp, with the few hooks the engine's own adapter
// (modules/shadows_engine) uses beyond the public API: the renderer's profiler and test read-backs.
#include <deque>
#include <memory>
#include <optional>

#include "cascades_pass.hpp"
#include "frame.hpp"
#include "geometry_store.hpp"
#include "izb_pass.hpp"
#include "ray_traced_pass.hpp"
#include "shadow_map_pass.hpp"
#include "shadows/context.hpp"

namespace shadows::detail {

class ContextImpl final : public Context {
 public:
  explicit ContextImpl(const ContextDesc& desc);
  ~ContextImpl() override;

  Capabilities capabilities() const override;
  Settings& settings() override { return settings_; }
  MeshId register_mesh(const MeshDesc& mesh) override;
  void unregister_mesh(MeshId mesh) override;
  MeshBounds mesh_bounds(MeshId mesh) const override;
  void record(VkCommandBuffer cmd, const FrameDesc& frame) override;
  void frame_completed(uint64_t frame_index) override;
  void set_collect_stats(bool enabled) override { collect_stats_ = enabled; }
  const Stats& stats() const override { return stats_; }
  std::vector<PassTime> pass_times() const override;
  std::vector<std::string> pass_names() const override;
  uint32_t validation_message_count() const override { return gpu_->validation_message_count(); }

  // Engine adapter hooks.
  engine::gpu::Context& gpu() { return *gpu_; }
  // Pass timings go to this profiler instead of the context's own (the renderer's, so its panel and
  // benchmark see the module's passes among its own). The caller collects it.
  void use_profiler(engine::gpu::GpuProfiler* profiler) { external_profiler_ = profiler; }
  CsmSnapshot read_csm() { return izb_ ? izb_->read_csm() : CsmSnapshot{}; }
  LitMapSnapshot read_lit_map() { return izb_ ? izb_->read_lit_map() : LitMapSnapshot{}; }
  const View& last_view() const { return view_; }

 private:
  struct Slot {
    std::optional<uint64_t> frame;  // recorded and not yet completed
    std::unique_ptr<engine::gpu::GpuProfiler> profiler;
    Technique technique = Technique::Off;
    bool csm = false;
    // Per light of the frame: its kind and which IZB and rt statistics records it made.
    struct LightRecords {
      std::string kind;
      uint32_t izb_first = 0, izb_count = 0, rt_first = 0, rt_count = 0;
      uint32_t faces = 0;  // a point light's cones recorded (Stats::LightStats::faces_recorded)
      bool reaches_view = true;  // Stats::LightStats::reaches_view
    };
    std::vector<LightRecords> lights;
  };

  void validate(const FrameDesc& frame) const;
  void validate_settings() const;  // the fields record refuses (Settings' documented ranges)
  void record_geometry(VkCommandBuffer cmd, const FrameDesc& frame, engine::gpu::GpuProfiler& profiler);
  void ensure_targets(VkExtent2D extent);
  // `clear`: `term` to 1 and (with a debug view) the overlay to 0, where no input pass does.
  void prepare_targets(VkCommandBuffer cmd, bool clear, const TermImage& term);
  template <typename RecordFaces>
  void record_point_light_faces(Frame& frame, RecordFaces&& record_faces);
  // A point light's cones that may reach the view (at least one), each a View of one face; sets
  // point_light_faces_recorded_.
  std::vector<View> point_light_face_views(const View& view);
  void record_local_light(Frame& frame, const Settings& settings);  // settings in world units
  static void set_light(View& view, const Light& light);
  // Between two lights: the previous light's accesses done; with `lit_start` `term` lit again.
  void restart_term(VkCommandBuffer cmd, bool lit_start, const TermImage& term);
  bool writes_every_pixel(const Light& light);
  bool reaches_view(const Light& light) const;
  void record_unreached_term(VkCommandBuffer cmd, const TermImage& term, const ShadingInputs& inputs);
  void record_light(Frame& frame, const Light& light, Slot::LightRecords& records);
  void clear_term_and_overlay(VkCommandBuffer cmd, const TermImage& term);
  // The HOST_OUTPUT_* bits of the output pass for an output (`with_overlay`: the overlay's light).
  uint32_t output_bits(const FrameDesc& frame, bool with_overlay) const;
  // Where light `i`'s passes write its term: the host's output itself where the output pass would
  // only copy the module's term into it, else the module's term.
  TermImage term_target(const FrameDesc& frame, uint32_t i) const;
  ShadingInputs shading_inputs(const FrameDesc& frame) const;
  void validate_light(const Light& light, const std::string& name) const;
  void check_paths(const Light& light, const std::string& name) const;
  Capabilities find_capabilities() const;
  void mark_needing_subgroup_operations(LightCapabilities& l) const;
  void record_inputs(VkCommandBuffer cmd, const FrameDesc& frame, const View& view);
  void record_technique(Frame& frame);
  void record_output(VkCommandBuffer cmd, const FrameDesc& frame, const ImageInput& output, bool with_overlay,
                     const ShadingInputs& inputs, const View& view);
  void complete_slot(Slot& slot);
  void add_memory(Stats& s, Technique technique, bool csm) const;
  IzbPass& izb();
  CascadesPass& cascades();

  std::unique_ptr<engine::gpu::Context> gpu_;
  bool cpu_paths_ = false;  // takes_cpu_paths
  uint32_t frames_in_flight_ = 2;
  Settings settings_;
  Stats stats_;
  bool collect_stats_ = true;
  uint32_t point_light_faces_recorded_ = 0;  // by the last record_point_light_faces (0: none ran)
  std::vector<Slot> slots_;
  engine::gpu::GpuProfiler* external_profiler_ = nullptr;
  std::vector<PassTime> last_pass_times_;

  GeometryStore geometry_;
  View view_;
  std::vector<DrawItem> draws_;
  struct OwnedInputs {  // written by the input pass when the host gives no native inputs
    engine::gpu::Image world_position, geometric_normal, albedo;
  } inputs_;
  engine::gpu::Image shadow_term_;
  engine::gpu::Image overlay_;
  VkExtent2D extent_{};
  engine::gpu::Buffer input_params_;  // HostInputs, written in the command buffer each frame
  engine::gpu::Sampler nearest_;
  engine::gpu::Pipeline inputs_pipeline_;
  // [R8, R16F, R32F][HOST_OUTPUT_* bits, at most 31], made on first use (output_pipeline).
  mutable std::optional<Capabilities> capabilities_;  // capabilities(), made once
  engine::gpu::Pipeline output_pipelines_[3][32];  // by format, HOST_OUTPUT_* bits
  const engine::gpu::Pipeline& output_pipeline(int format, uint32_t what);
  void record_output_pass(VkCommandBuffer cmd, const engine::gpu::Pipeline& p, VkImageView out, VkImageView overlay_out,
                          const ShadingInputs& inputs, const View& view);
  engine::gpu::Image dummy_input_;              // bound where an optional input is absent
  bool targets_fresh_ = false;                  // just created: UNDEFINED until the first barrier

  std::unique_ptr<ShadowMapPass> shadow_map_;
  std::unique_ptr<IzbPass> izb_;
  std::unique_ptr<CascadesPass> cascades_;
  std::unique_ptr<RayTracedPass> ray_traced_;
};

}  // namespace shadows::detail
