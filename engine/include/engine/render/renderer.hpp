#pragma once
// Frame orchestration: ECS update -> G-buffer -> shading points -> features (the shadow module) ->
// lighting. The renderer owns the G-buffer and the per-pixel shadow term that features write and
// lighting reads; it knows nothing about how shadows are made.
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/assets/scene.hpp"
#include "engine/core/material_textures.hpp"
#include "gpu/context.hpp"
#include "gpu/pipeline.hpp"
#include "gpu/profiler.hpp"
#include "gpu/resources.hpp"

namespace engine {

// All meshes of a scene in one vertex buffer and one index buffer (also bound as storage buffers,
// so passes can fetch triangles).
struct GpuMeshRange {
  uint32_t first_index = 0;
  uint32_t index_count = 0;
  int32_t vertex_offset = 0;
  uint32_t vertex_count = 0;
  // A deformable entity's own copy of its mesh's vertices, which skinning.comp rewrites every frame:
  // its index in SceneGeometry::deformed(), and the slot of the mesh's rest vertices (the same
  // triangles). UINT32_MAX / its own slot for every other mesh.
  uint32_t deformed = UINT32_MAX;
  uint32_t rest_mesh = UINT32_MAX;
};

// A deformable entity (MeshData::deform with a Skeleton or morph targets) and where its data lives.
struct DeformedMesh {
  Entity entity;
  uint32_t mesh = 0;       // its own slot
  uint32_t rest_mesh = 0;  // the slot of its mesh's rest vertices
  uint32_t skin_word = UINT32_MAX;  // first word of its skin in deform_data(), UINT32_MAX unskinned
  uint32_t morph_word = 0;          // first word of its morph deltas
  uint32_t target_count = 0;
  uint32_t joint_count = 0;
};

class SceneGeometry {
 public:
  SceneGeometry(gpu::Context& ctx, Registry& registry);
  const gpu::Buffer& vertices() const { return vertices_; }
  const gpu::Buffer& indices() const { return indices_; }
  // Every material texture (shared/material.h); bind as a storage buffer.
  const gpu::Buffer& textures() const { return textures_; }
  const MaterialTextureTable& texture_table() const { return texture_table_; }
  const GpuMeshRange& mesh(uint32_t slot) const { return meshes_.at(slot); }
  size_t mesh_count() const { return meshes_.size(); }
  uint64_t triangle_count() const { return total_indices_ / 3; }
  // Deformable entities, each with its own slot; their skins and morph deltas (shared/skinning.h's
  // layout) in one storage buffer (null when there are none).
  const std::vector<DeformedMesh>& deformed() const { return deformed_; }
  const gpu::Buffer& deform_data() const { return deform_data_; }

 private:
  void add_deformed(Registry& registry, std::vector<Vertex>& vertices, std::vector<uint32_t>& deform_words);

  std::vector<DeformedMesh> deformed_;
  gpu::Buffer deform_data_;
  gpu::Buffer vertices_;
  gpu::Buffer indices_;
  gpu::Buffer textures_;
  MaterialTextureTable texture_table_;
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
  uint32_t alpha_threshold = 0;               // engine::alpha_threshold (0: not alpha-tested)
  uint32_t base_color_texture = 0xffffffffu;  // SceneGeometry::texture_table() index, or none
  bool alpha_tested() const { return alpha_threshold != 0; }
  ShadowCaster shadow;  // defaults when the entity has none
  Aabb bounds;          // world space
  // A deformed entity's (SceneGeometry::mesh(mesh).deformed set): this frame's box around its
  // deformed vertices, in object space.
  Aabb deformed_bounds;
};

// A spot or point light the lighting pass adds beside the sun, with its own shadow term.
enum class LocalLightKind : uint32_t { Spot, Point };
struct FrameLight {
  Entity entity;
  LocalLightKind kind = LocalLightKind::Point;
  glm::vec3 position{0.0f};
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  // spot: the direction light travels, unit
  glm::vec3 radiance{0.0f};                 // colour * intensity (candela)
  float range = 0.0f;                       // world units
  float inner_cone = 0.0f, outer_cone = 0.0f;  // spot: half angles, radians
  float radius = 0.0f;                      // the emitting sphere's, world units (SpotLight/PointLight::radius)
};

// Every world-space value of a frame (FrameView's matrices and positions, DrawItem::world and bounds,
// FrameLight::position, the G-buffer's world positions) is relative to FrameView::origin, a world
// position in double near the camera (Renderer::world_origin), so float keeps its precision however
// far the camera is from the world's origin. A scene near the origin (within 4096 near planes of the
// camera) keeps origin 0.
struct FrameView {
  glm::dvec3 origin{0.0};
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};
  glm::mat4 view_projection{1.0f};
  glm::mat4 inverse_view_projection{1.0f};
  glm::vec3 camera_position{0.0f};
  glm::vec3 light_direction{0.0f, -1.0f, 0.0f};  // travel direction, unit
  glm::vec3 light_radiance{1.0f};
  float light_angular_diameter_degrees = 0.53f;  // the sun's (DirectionalLight::angular_diameter_degrees)
  // Enabled spot and point lights whose reach (a point light's ball of its range, a spot light's cone
  // within it) may meet the view, nearest first (by the ball), at most Renderer::kMaxLocalLights.
  std::vector<FrameLight> local_lights;
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
  gpu::Image terminator_offset;  // RGBA16F: xyz smooth-terminator offset of the shading point (gbuffer.frag)
  gpu::Image world_position;  // RGBA32F: reconstructed from depth; w = 1 covered, 0 background
  VkExtent2D extent{};
};

struct FrameContext {
  gpu::Context& ctx;
  VkCommandBuffer cmd;
  gpu::GpuProfiler& profiler;
  const FrameView& view;
  GBuffer& gbuffer;
  gpu::Image& shadow_term;     // R32F storage image, the sun's: 1 (lit) in every pixel no feature writes
  gpu::Image* local_shadow_terms;  // view.local_lights.size() images as shadow_term, one per local light
  gpu::Image& overlay;         // RGBA8 storage image, 0 where no feature writes; lighting blends rgb by a
  const gpu::Buffer& frame_uniforms;
  SceneGeometry& geometry;
  const std::vector<DrawItem>& draws;
  Registry& registry;
  // What the features wrote every pixel of this frame (kWroteSunTerm | kWroteOverlay | kWroteLocalTerm
  // << i), set by a feature's record(). Lighting then reads those as written; the renderer sets the
  // others to their rest values (terms 1, overlay 0) after the features, where they do not hold them
  // already, so that a full-screen clear runs only where no feature writes.
  uint32_t written = 0;
  static constexpr uint32_t kWroteSunTerm = 1u, kWroteOverlay = 2u, kWroteLocalTerm = 4u;
};

// A plug-in stage that runs after the G-buffer and before lighting (the shadow module is one).
class RenderFeature {
 public:
  virtual ~RenderFeature() = default;
  virtual std::string name() const = 0;
  virtual void on_scene(gpu::Context&, Scene&, SceneGeometry&) {}
  virtual void on_resize(gpu::Context&, VkExtent2D) {}
  virtual void record(FrameContext& frame) = 0;
  // After a frame's fence, once per frame in the order they were recorded (Renderer::completed_frame()
  // names it): read back statistics, grow pools.
  virtual void after_frame(gpu::Context&) {}
  // Draws the feature's ImGui controls (windowed mode only).
  virtual void draw_ui() {}
};

class MeshDeformer;  // engine/render/mesh_deformer.hpp

class Renderer {
 public:
  static constexpr uint32_t kMaxFramesInFlight = 3;
  static constexpr uint32_t kMaxLocalLights = 3;  // shadowed spot and point lights per frame (lighting.comp)

  // `frames_in_flight` (1..kMaxFramesInFlight): how many recorded frames the host may have on the GPU
  // at once. Frame N uses the per-frame data of slot N % frames_in_flight; before update() for frame N
  // the host has waited for frame N - frames_in_flight and called after_frame() for it. G-buffer and
  // other GPU-only targets are shared: one queue runs the frames in order.
  Renderer(gpu::Context& ctx, VkExtent2D extent, uint32_t frames_in_flight = 1);
  ~Renderer();
  uint32_t frames_in_flight() const { return frames_in_flight_; }

  void set_scene(Scene& scene);
  Scene* scene() { return scene_; }
  void add_feature(std::shared_ptr<RenderFeature> feature);
  const std::vector<std::shared_ptr<RenderFeature>>& features() const { return features_; }
  void resize(VkExtent2D extent);
  VkExtent2D extent() const { return extent_; }

  // Runs the ECS systems (transforms, camera), builds the draw list and writes the frame's uniforms
  // (slot frame_index % frames_in_flight).
  void update(float dt);
  // Records G-buffer, shading points, features, lighting into `cmd`. Leaves output() in GENERAL. The
  // frame then counts as pending until after_frame().
  void record(VkCommandBuffer cmd);
  // The oldest pending frame's commands completed: collects its GPU times and calls the features'
  // after_frame. Does nothing when no frame is pending.
  void after_frame();
  // Waits for the device and completes every pending frame (resize, scene change, shutdown).
  void finish_frames();
  // Frames recorded and not yet completed by after_frame().
  size_t frames_pending() const { return pending_.size(); }
  // The frame the current (or last) after_frame() completed.
  uint64_t completed_frame() const { return completed_frame_; }
  // update + record + submit + wait + after_frame, for headless use.
  void render_frame(float dt = 1.0f / 60.0f);

  // When set, lighting takes its shadow term from this host image (1 = lit) instead of the features:
  // used to show the reference tracer's answer. Clear with an empty vector.
  void set_external_shadow_term(std::vector<float> term);

  // The smooth-terminator offset of the shading points (gbuffer.frag; on by default). Off only to
  // measure the faceted terminator it removes.
  void set_smooth_terminator(bool on) { smooth_terminator_ = on; }
  bool smooth_terminator() const { return smooth_terminator_; }

  gpu::Image& output() { return output_; }
  GBuffer& gbuffer() { return gbuffer_; }
  gpu::Image& shadow_term() { return shadow_term_; }
  // Local light i's shadow term (FrameView::local_lights[i]).
  gpu::Image& local_shadow_term(uint32_t i) { return local_shadow_terms_.at(i); }
  const FrameView& frame_view() const { return view_; }
  // The world position (double, Scene::origin included) that this frame's world-space values are
  // relative to: see FrameView.
  const glm::dvec3& world_origin() const { return view_.origin; }
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
  std::vector<float> read_local_shadow_term(uint32_t i);
  void write_png(const std::filesystem::path& path);

 private:
  void create_targets();
  void record_frame(VkCommandBuffer cmd);
  void build_draw_list();
  void gather_local_lights();

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
  std::vector<gpu::Image> local_shadow_terms_;  // kMaxLocalLights
  gpu::Image overlay_;
  // Which of the sun's term, the overlay and the local terms hold their rest values (FrameContext::written's
  // bits): left by the renderer's own clear and written by nothing since.
  uint32_t at_rest_ = 0;
  void rest_unwritten(VkCommandBuffer cmd, uint32_t written);
  gpu::Image output_;
  uint32_t frames_in_flight_ = 1;
  std::vector<gpu::Buffer> frame_uniforms_;  // one per frame-in-flight slot: written by the host each frame
  uint64_t next_frame_ = 0;                  // index of the next frame recorded
  std::deque<uint64_t> pending_;             // recorded, not completed; oldest first
  uint64_t completed_frame_ = 0;
  gpu::Buffer external_shadow_;
  bool use_external_shadow_ = false;
  bool smooth_terminator_ = true;
  gpu::Sampler nearest_sampler_;
  gpu::Pipeline gbuffer_pipeline_;
  gpu::Pipeline shading_points_pipeline_;
  gpu::Pipeline lighting_pipeline_;        // the sun alone
  gpu::Pipeline local_lighting_pipeline_;  // the sun and FrameView::local_lights
  gpu::GpuProfiler profiler_;
  std::unique_ptr<MeshDeformer> deformer_;  // poses and deforms SceneGeometry::deformed() each frame
  VkCommandBuffer frame_cmd_ = VK_NULL_HANDLE;
  VkFence frame_fence_ = VK_NULL_HANDLE;
};

// Writes tightly packed RGBA8 pixels as a PNG; throws std::runtime_error naming the path on failure.
void write_rgba8_png(const std::filesystem::path& path, uint32_t width, uint32_t height, const uint8_t* rgba);

}  // namespace engine
