#pragma once
// Frame orchestration: ECS update -> G-buffer -> shading points -> features (the shadow module) ->
// lighting. The renderer owns the G-buffer and the per-pixel shadow term that features write and
// lighting reads; it knows nothing about how shadows are made.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/assets/scene.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/pipeline.hpp"
#include "engine/gpu/profiler.hpp"
#include "engine/gpu/resources.hpp"

namespace engine {

// All meshes of a scene in one vertex buffer and one index buffer (also bound as storage buffers,
// so passes can fetch triangles).
struct GpuMeshRange {
  uint32_t first_index = 0;
  uint32_t index_count = 0;
  int32_t vertex_offset = 0;
  uint32_t vertex_count = 0;
};

class SceneGeometry {
 public:
  SceneGeometry(gpu::Context& ctx, Registry& registry);
  const gpu::Buffer& vertices() const { return vertices_; }
  const gpu::Buffer& indices() const { return indices_; }
  const GpuMeshRange& mesh(uint32_t slot) const { return meshes_.at(slot); }
  size_t mesh_count() const { return meshes_.size(); }
  uint64_t triangle_count() const { return total_indices_ / 3; }

 private:
  gpu::Buffer vertices_;
  gpu::Buffer indices_;
  std::vector<GpuMeshRange> meshes_;
  uint64_t total_indices_ = 0;
};

// One drawable entity this frame.
struct DrawItem {
  Entity entity;
  glm::mat4 world{1.0f};
  uint32_t mesh = 0;  // SceneGeometry slot
  glm::vec4 base_color{1.0f};
  AlphaMode alpha_mode = AlphaMode::Opaque;
  float alpha_cutoff = 0.5f;
  ShadowCaster shadow;  // defaults when the entity has none
  Aabb bounds;          // world space
};

struct FrameView {
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};
  glm::mat4 view_projection{1.0f};
  glm::mat4 inverse_view_projection{1.0f};
  glm::vec3 camera_position{0.0f};
  glm::vec3 light_direction{0.0f, -1.0f, 0.0f};  // travel direction, unit
  glm::vec3 light_radiance{1.0f};
  float near_plane = 0.05f;
  float far_plane = 200.0f;
  float vertical_fov = 1.0f;
  VkExtent2D extent{};
  uint64_t frame_index = 0;
};

struct GBuffer {
  gpu::Image depth;           // D32, reversed Z (1 near, 0 far/background)
  gpu::Image albedo;          // RGBA8: base colour, a = receives-shadow flag
  gpu::Image normal;          // RGBA16F: shading normal, facing the camera
  gpu::Image geometric_normal;// RGBA16F: triangle normal in world space, facing the camera
  gpu::Image world_position;  // RGBA32F: reconstructed from depth; w = 1 covered, 0 background
  VkExtent2D extent{};
};

struct FrameContext {
  gpu::Context& ctx;
  VkCommandBuffer cmd;
  gpu::GpuProfiler& profiler;
  const FrameView& view;
  GBuffer& gbuffer;
  gpu::Image& shadow_term;     // R32F storage image, cleared to 1 (lit) before features run
  gpu::Image& overlay;         // RGBA8 storage image, cleared to 0; lighting blends rgb by a
  const gpu::Buffer& frame_uniforms;
  SceneGeometry& geometry;
  const std::vector<DrawItem>& draws;
  Registry& registry;
};

// A plug-in stage that runs after the G-buffer and before lighting (the shadow module is one).
class RenderFeature {
 public:
  virtual ~RenderFeature() = default;
  virtual std::string name() const = 0;
  virtual void on_scene(gpu::Context&, Scene&, SceneGeometry&) {}
  virtual void on_resize(gpu::Context&, VkExtent2D) {}
  virtual void record(FrameContext& frame) = 0;
  // After the frame's fence: read back statistics, grow pools.
  virtual void after_frame(gpu::Context&) {}
  // Draws the feature's ImGui controls (windowed mode only).
  virtual void draw_ui() {}
};

class Renderer {
 public:
  Renderer(gpu::Context& ctx, VkExtent2D extent);
  ~Renderer();

  void set_scene(Scene& scene);
  Scene* scene() { return scene_; }
  void add_feature(std::shared_ptr<RenderFeature> feature);
  const std::vector<std::shared_ptr<RenderFeature>>& features() const { return features_; }
  void resize(VkExtent2D extent);
  VkExtent2D extent() const { return extent_; }

  // Runs the ECS systems (transforms, camera) and builds the draw list.
  void update(float dt);
  // Records G-buffer, shading points, features, lighting into `cmd`. Leaves output() in GENERAL.
  void record(VkCommandBuffer cmd);
  // After the frame's commands completed.
  void after_frame();
  // update + record + submit + wait + after_frame, for headless use.
  void render_frame(float dt = 1.0f / 60.0f);

  // When set, lighting takes its shadow term from this host image (1 = lit) instead of the features:
  // used to show the reference tracer's answer. Clear with an empty vector.
  void set_external_shadow_term(std::vector<float> term);

  gpu::Image& output() { return output_; }
  GBuffer& gbuffer() { return gbuffer_; }
  gpu::Image& shadow_term() { return shadow_term_; }
  const FrameView& frame_view() const { return view_; }
  const std::vector<DrawItem>& draws() const { return draws_; }
  SceneGeometry* geometry() { return geometry_.get(); }
  gpu::GpuProfiler& profiler() { return profiler_; }
  gpu::Context& context() { return ctx_; }
  SystemSchedule& systems() { return systems_; }

  // Readbacks (wait for the queue). Pixel (x, y) at index y * width + x.
  std::vector<uint8_t> read_output_rgba8();
  std::vector<glm::vec4> read_world_positions();
  std::vector<glm::vec4> read_geometric_normals();
  std::vector<float> read_depth();
  std::vector<float> read_shadow_term();
  void write_png(const std::filesystem::path& path);

 private:
  void create_targets();
  void build_draw_list();

  gpu::Context& ctx_;
  VkExtent2D extent_;
  Scene* scene_ = nullptr;
  std::unique_ptr<SceneGeometry> geometry_;
  std::vector<std::shared_ptr<RenderFeature>> features_;
  std::vector<DrawItem> draws_;
  FrameView view_;
  SystemSchedule systems_;
  GBuffer gbuffer_;
  gpu::Image shadow_term_;
  gpu::Image overlay_;
  gpu::Image output_;
  gpu::Buffer frame_uniforms_;
  gpu::Buffer external_shadow_;
  bool use_external_shadow_ = false;
  gpu::Sampler nearest_sampler_;
  gpu::Pipeline gbuffer_pipeline_;
  gpu::Pipeline shading_points_pipeline_;
  gpu::Pipeline lighting_pipeline_;
  gpu::GpuProfiler profiler_;
  VkCommandBuffer frame_cmd_ = VK_NULL_HANDLE;
  VkFence frame_fence_ = VK_NULL_HANDLE;
};

// Writes tightly packed RGBA8 pixels as a PNG; throws std::runtime_error naming the path on failure.
void write_rgba8_png(const std::filesystem::path& path, uint32_t width, uint32_t height, const uint8_t* rgba);

}  // namespace engine
