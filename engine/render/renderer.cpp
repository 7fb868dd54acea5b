#include "engine/render/renderer.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>
#include <stb_image_write.h>

#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"
#include "mesh_deformer.hpp"
#include "shared/frame.h"

namespace engine {

using namespace gpu;

namespace {
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr VkFormat kAlbedoFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr VkFormat kNormalFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
constexpr VkFormat kWorldPositionFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
constexpr VkFormat kShadowFormat = VK_FORMAT_R32_SFLOAT;
constexpr VkFormat kOutputFormat = VK_FORMAT_R8G8B8A8_UNORM;

uint32_t groups(uint32_t n, uint32_t size) { return (n + size - 1) / size; }

const VkPipelineStageFlags2 kAllStages = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
const VkAccessFlags2 kAllAccess = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT;
}  // namespace

SceneGeometry::SceneGeometry(gpu::Context& ctx, Registry& registry) {
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;
  std::unordered_map<const MeshData*, uint32_t> slots;
  registry.each<Mesh>([&](Entity, Mesh& mesh) {
    if (!mesh.data) return;
    auto it = slots.find(mesh.data.get());
    if (it != slots.end()) {
      mesh.gpu_mesh = it->second;
      return;
    }
    GpuMeshRange range;
    range.first_index = static_cast<uint32_t>(indices.size());
    range.index_count = static_cast<uint32_t>(mesh.data->indices.size());
    range.vertex_offset = static_cast<int32_t>(vertices.size());
    range.vertex_count = static_cast<uint32_t>(mesh.data->vertices.size());
    vertices.insert(vertices.end(), mesh.data->vertices.begin(), mesh.data->vertices.end());
    indices.insert(indices.end(), mesh.data->indices.begin(), mesh.data->indices.end());
    mesh.gpu_mesh = static_cast<uint32_t>(meshes_.size());
    range.rest_mesh = mesh.gpu_mesh;
    slots[mesh.data.get()] = mesh.gpu_mesh;
    meshes_.push_back(range);
  });
  std::vector<uint32_t> deform_words;
  add_deformed(registry, vertices, deform_words);
  if (!deform_words.empty())
    deform_data_ = upload_buffer(ctx, deform_words.data(), deform_words.size() * sizeof(uint32_t),
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "deform data");
  total_indices_ = indices.size();
  texture_table_ = MaterialTextureTable(registry);
  textures_ = upload_buffer(ctx, texture_table_.words().data(), texture_table_.words().size() * sizeof(uint32_t),
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, "material textures");
  VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  // Where the device ray traces, the same buffers feed acceleration structure builds.
  if (ctx.features().acceleration_structure)
    usage |= VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
             VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  vertices_ = upload_buffer(ctx, vertices.data(), vertices.size() * sizeof(Vertex),
                            usage | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "scene vertices");
  indices_ = upload_buffer(ctx, indices.data(), indices.size() * sizeof(uint32_t),
                           usage | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, "scene indices");
}

void SceneGeometry::add_deformed(Registry& registry, std::vector<Vertex>& vertices, std::vector<uint32_t>& deform_words) {
  // One copy of each mesh's skin and morph deltas, however many entities it deforms.
  std::unordered_map<const DeformData*, std::pair<uint32_t, uint32_t>> words;
  const auto append_vec3 = [&](const glm::vec3& v) {
    for (int k = 0; k < 3; ++k) deform_words.push_back(std::bit_cast<uint32_t>(v[k]));
  };
  registry.each<Mesh>([&](Entity e, Mesh& mesh) {
    if (!mesh.data || !mesh.data->deform || mesh.gpu_mesh == UINT32_MAX) return;
    const DeformData& data = *mesh.data->deform;
    const Skeleton* skeleton = registry.try_get<Skeleton>(e);
    const bool skinned = data.skinned() && skeleton && !skeleton->joints.empty();
    if (!skinned && data.morph_targets.empty()) return;
    const uint32_t n = uint32_t(mesh.data->vertices.size());
    auto [it, added] = words.try_emplace(&data, UINT32_MAX, 0u);
    if (added) {
      if (data.skinned()) {
        it->second.first = uint32_t(deform_words.size());
        for (uint32_t v = 0; v < n; ++v) {
          for (int k = 0; k < 4; ++k) deform_words.push_back(data.joints[v][k]);
          for (int k = 0; k < 4; ++k) deform_words.push_back(std::bit_cast<uint32_t>(data.weights[v][k]));
        }
      }
      it->second.second = uint32_t(deform_words.size());
      for (const MorphTarget& t : data.morph_targets)
        for (uint32_t v = 0; v < n; ++v) {
          append_vec3(t.position_deltas[v]);
          append_vec3(t.normal_deltas.empty() ? glm::vec3(0.0f) : t.normal_deltas[v]);
        }
    }
    DeformedMesh d;
    d.entity = e;
    d.rest_mesh = mesh.gpu_mesh;
    d.mesh = uint32_t(meshes_.size());
    d.skin_word = skinned ? it->second.first : UINT32_MAX;
    d.morph_word = it->second.second;
    d.target_count = uint32_t(data.morph_targets.size());
    d.joint_count = skinned ? std::max<uint32_t>(data.joint_count, uint32_t(skeleton->joints.size())) : 0u;
    GpuMeshRange own = meshes_[d.rest_mesh];
    own.vertex_offset = int32_t(vertices.size());
    own.deformed = uint32_t(deformed_.size());
    own.rest_mesh = d.rest_mesh;
    // Starts as the rest pose; skinning.comp rewrites positions and normals every frame.
    vertices.insert(vertices.end(), mesh.data->vertices.begin(), mesh.data->vertices.end());
    meshes_.push_back(own);
    mesh.gpu_mesh = d.mesh;
    deformed_.push_back(d);
  });
}

Renderer::Renderer(gpu::Context& ctx, VkExtent2D extent, uint32_t frames_in_flight)
    // 256 regions: a point light runs the IZB once per cube face, six times the passes of the sun.
    : ctx_(ctx), extent_(extent), frames_in_flight_(frames_in_flight), profiler_(ctx, 256, 4096, frames_in_flight) {
  if (extent.width == 0 || extent.height == 0) throw std::invalid_argument("render size must be non-zero");
  if (frames_in_flight < 1 || frames_in_flight > kMaxFramesInFlight)
    throw std::invalid_argument("frames in flight must be 1.." + std::to_string(kMaxFramesInFlight) + ", not " +
                                std::to_string(frames_in_flight));
  for (uint32_t i = 0; i < frames_in_flight_; ++i)
    frame_uniforms_.emplace_back(ctx, sizeof(gpu_shared::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true,
                                 "frame uniforms " + std::to_string(i));
  nearest_sampler_ = Sampler(ctx, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "nearest clamp");

  PipelineFactory factory(ctx);
  GraphicsPipelineDesc g;
  g.name = "gbuffer";
  g.vertex_shader = "gbuffer.vert";
  g.fragment_shader = "gbuffer.frag";
  g.bindings = {{gpu_shared::GBUFFER_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
                {gpu_shared::GBUFFER_BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                {gpu_shared::GBUFFER_BINDING_INDICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                {gpu_shared::GBUFFER_BINDING_TEXTURES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}};
  g.push_constant_size = sizeof(gpu_shared::DrawPush);
  g.vertex_input = VertexInput::None;  // gbuffer.vert reads its triangle from the buffers
  g.color_formats = {kAlbedoFormat, kNormalFormat, kNormalFormat, kNormalFormat};
  g.depth_format = kDepthFormat;
  g.cull_mode = VK_CULL_MODE_NONE;  // glTF single-sided surfaces still occlude and must be seen from both sides
  gbuffer_pipeline_ = factory.graphics(g);

  shading_points_pipeline_ = factory.compute(
      {"shading_points.comp",
       {{gpu_shared::SHADING_POINTS_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
        {gpu_shared::SHADING_POINTS_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
        {gpu_shared::SHADING_POINTS_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SHADING_POINTS_BINDING_TERMINATOR_OFFSET, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
       0});
  std::vector<Binding> lighting_bindings = {
      {gpu_shared::LIGHTING_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
      {gpu_shared::LIGHTING_BINDING_ALBEDO, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
      {gpu_shared::LIGHTING_BINDING_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
      {gpu_shared::LIGHTING_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
      {gpu_shared::LIGHTING_BINDING_SHADOW, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
      {gpu_shared::LIGHTING_BINDING_OVERLAY, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
      {gpu_shared::LIGHTING_BINDING_OUTPUT, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}};
  lighting_pipeline_ = factory.compute({"lighting.comp", lighting_bindings, 0});
  for (uint32_t i = 0; i < kMaxLocalLights; ++i)
    lighting_bindings.push_back({gpu_shared::LIGHTING_BINDING_LOCAL_SHADOW + i, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE});
  local_lighting_pipeline_ = factory.compute({"lighting_local_lights.comp", lighting_bindings, 0});
  static_assert(kMaxLocalLights == gpu_shared::kMaxLocalLights && kMaxLocalLights == 3);

  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = ctx.command_pool();
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VK_CHECK(vkAllocateCommandBuffers(ctx.device(), &alloc, &frame_cmd_));
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VK_CHECK(vkCreateFence(ctx.device(), &fence_info, ctx.allocator(), &frame_fence_));
  deformer_ = std::make_unique<MeshDeformer>(ctx, frames_in_flight_);
  create_targets();
}

Renderer::~Renderer() {
  finish_frames();  // the features hear about every frame they recorded
  features_.clear();
  if (frame_fence_) vkDestroyFence(ctx_.device(), frame_fence_, ctx_.allocator());
  if (frame_cmd_) vkFreeCommandBuffers(ctx_.device(), ctx_.command_pool(), 1, &frame_cmd_);
}

void Renderer::create_targets() {
  const VkExtent2D e = extent_;
  const VkImageUsageFlags color = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
                                  VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  const VkImageUsageFlags storage = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                    VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  gbuffer_.extent = e;
  gbuffer_.depth = Image(ctx_, e, kDepthFormat,
                         VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                             VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                         "gbuffer depth");
  gbuffer_.albedo = Image(ctx_, e, kAlbedoFormat, color, "gbuffer albedo");
  gbuffer_.normal = Image(ctx_, e, kNormalFormat, color, "gbuffer normal");
  gbuffer_.geometric_normal = Image(ctx_, e, kNormalFormat, color, "gbuffer geometric normal");
  gbuffer_.terminator_offset = Image(ctx_, e, kNormalFormat, color, "gbuffer terminator offset");
  gbuffer_.world_position = Image(ctx_, e, kWorldPositionFormat, storage, "world position");
  shadow_term_ = Image(ctx_, e, kShadowFormat, storage, "shadow term");
  local_shadow_terms_.clear();
  for (uint32_t i = 0; i < kMaxLocalLights; ++i)
    local_shadow_terms_.emplace_back(ctx_, e, kShadowFormat, storage, "local light shadow term");
  overlay_ = Image(ctx_, e, kOutputFormat, storage, "debug overlay");
  output_ = Image(ctx_, e, kOutputFormat, storage | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, "lit output");
  ctx_.immediate_submit([&](VkCommandBuffer cmd) {
    for (Image* img : {&gbuffer_.depth, &gbuffer_.albedo, &gbuffer_.normal, &gbuffer_.geometric_normal,
                       &gbuffer_.terminator_offset,
                       &gbuffer_.world_position, &shadow_term_, &overlay_, &output_})
      img->transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, kAllStages, kAllAccess);
    for (Image& img : local_shadow_terms_)
      img.transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, kAllStages, kAllAccess);
  });
  at_rest_ = 0;  // new images hold nothing yet
}

void Renderer::resize(VkExtent2D extent) {
  if (extent.width == 0 || extent.height == 0) return;
  if (extent.width == extent_.width && extent.height == extent_.height) return;
  finish_frames();  // the targets are replaced; pending frames' results are read first
  extent_ = extent;
  create_targets();
  use_external_shadow_ = false;
  for (auto& f : features_) f->on_resize(ctx_, extent_);
}

void Renderer::set_scene(Scene& scene) {
  finish_frames();
  scene_ = &scene;
  update_world_transforms(scene.registry);
  geometry_ = std::make_unique<SceneGeometry>(ctx_, scene.registry);
  for (auto& f : features_) f->on_scene(ctx_, scene, *geometry_);
}

void Renderer::add_feature(std::shared_ptr<RenderFeature> feature) {
  if (scene_) feature->on_scene(ctx_, *scene_, *geometry_);
  feature->on_resize(ctx_, extent_);
  features_.push_back(std::move(feature));
}

namespace {

// The frame's local origin (FrameView): 0 while the camera is within 4096 near planes of the world's
// origin (float then holds the scene as well as the depth buffer does), else the camera's position
// rounded to a power-of-two cell of about 64 near planes, so the origin moves in steps rather than
// every frame and every coordinate stays within the view's own scale.
glm::dvec3 choose_world_origin(const glm::dvec3& eye, double near_plane) {
  const double reach = std::max({std::abs(eye.x), std::abs(eye.y), std::abs(eye.z)});
  if (!(reach > 4096.0 * near_plane)) return glm::dvec3(0.0);
  const double cell = std::exp2(std::round(std::log2(64.0 * near_plane)));
  return glm::round(eye / cell) * cell;
}

}  // namespace

void Renderer::build_draw_list() {
  draws_.clear();
  const glm::dvec3 shift = scene_->origin - view_.origin;
  scene_->registry.each<Mesh, Transform>([&](Entity e, Mesh& mesh, Transform& t) {
    if (mesh.gpu_mesh == UINT32_MAX) return;
    DrawItem d;
    d.entity = e;
    d.world = rebased(t.world, shift);
    d.mesh = mesh.gpu_mesh;
    if (const GpuMeshRange& range = geometry_->mesh(d.mesh); range.deformed != UINT32_MAX) {
      d.deformed_bounds = deformer_->bounds(range.deformed);
      d.bounds = d.deformed_bounds.transformed(d.world);
    } else if (mesh.data) {
      d.bounds = mesh.data->bounds.transformed(d.world);
    }
    if (const auto* m = scene_->registry.try_get<Material>(e)) {
      d.base_color = m->base_color;
      d.alpha_mode = m->alpha_mode;
      d.alpha_cutoff = m->alpha_cutoff;
      d.alpha_threshold = alpha_threshold(*m);
      d.base_color_texture = geometry_->texture_table().index_of(*m);
    }
    if (const auto* s = scene_->registry.try_get<ShadowCaster>(e)) d.shadow = *s;
    draws_.push_back(d);
  });
}

namespace {

struct ReachSphere {
  glm::vec3 centre;
  float radius;
};

// A sphere holding every point a light reaches: a point light's ball of its range; a spot light's
// part of that ball within its outer cone (half angle a, range r), held by the sphere through its apex
// and its rim, centred r / (2 cos a) along its axis (which holds its cap too), where that is smaller
// than the ball (a < 60 degrees).
ReachSphere reach_sphere(const FrameLight& l) {
  const float cos_outer = std::cos(l.outer_cone);
  if (l.kind != LocalLightKind::Spot || cos_outer <= 0.5f) return {l.position, l.range};
  const float radius = l.range / (2.0f * cos_outer);
  // (A rounding step wider: the sphere must hold the whole part, not nearly.)
  return {l.position + l.direction * radius, radius * (1.0f + 1.0e-5f) + 1.0e-6f * l.range};
}

}  // namespace

void Renderer::gather_local_lights() {
  view_.local_lights.clear();
  Registry& r = scene_->registry;
  auto add = [&](Entity e, LocalLightKind kind, const glm::vec3& color, float intensity, float range,
                 float inner_cone, float outer_cone, float radius) {
    const auto* t = r.try_get<Transform>(e);
    if (!t || !(intensity > 0.0f) || !(range > 0.0f)) return;
    FrameLight l;
    l.entity = e;
    l.kind = kind;
    l.position = glm::vec3(rebased(t->world, scene_->origin - view_.origin)[3]);
    l.direction = glm::normalize(-glm::vec3(t->world[2]));  // glTF: a spot light shines down local -Z
    l.radiance = color * intensity;
    l.range = range;
    l.inner_cone = inner_cone;
    l.outer_cone = outer_cone;
    l.radius = radius;
    // A light whose reach lies outside the view (beside it, or wholly behind the camera: every point
    // seen has a positive w) lights no pixel: no pass runs for it, and it takes no slot from one that does.
    const ReachSphere sphere = reach_sphere(l);
    Aabb reach;
    reach.extend(sphere.centre - glm::vec3(sphere.radius));
    reach.extend(sphere.centre + glm::vec3(sphere.radius));
    if (reach.outside_clip(view_.view_projection, glm::vec4(-1.0f, -1.0f, 1.0f, 1.0f), 0.0f)) return;
    view_.local_lights.push_back(l);
  };
  r.each<SpotLight>([&](Entity e, SpotLight& s) {
    if (s.enabled) add(e, LocalLightKind::Spot, s.color, s.intensity, s.range, s.inner_cone, s.outer_cone, s.radius);
  });
  r.each<PointLight>([&](Entity e, PointLight& p) {
    if (p.enabled) add(e, LocalLightKind::Point, p.color, p.intensity, p.range, 0.0f, 0.0f, p.radius);
  });
  // The nearest lights (by the distance to their sphere of reach) when there are more than the pass takes.
  std::stable_sort(view_.local_lights.begin(), view_.local_lights.end(), [&](const FrameLight& a, const FrameLight& b) {
    return glm::distance(a.position, view_.camera_position) - a.range <
           glm::distance(b.position, view_.camera_position) - b.range;
  });
  if (view_.local_lights.size() > kMaxLocalLights) view_.local_lights.resize(kMaxLocalLights);
}

void Renderer::update(float dt) {
  if (!scene_) throw std::logic_error("Renderer::update before set_scene");
  systems_.run(scene_->registry, dt);
  update_world_transforms(scene_->registry);
  const float aspect = float(extent_.width) / float(extent_.height);
  update_camera(scene_->registry, scene_->camera, aspect);

  const auto& cam = scene_->registry.get<Camera>(scene_->camera);
  const auto& cam_t = scene_->registry.get<Transform>(scene_->camera);
  // The view relative to the frame's origin: its rotation as it is, its translation from the eye's
  // position relative to that origin, in double (the scene-space view's own translation has already
  // lost what a far camera's float position cannot hold).
  const glm::dvec3 eye_world = scene_->origin + glm::dvec3(cam_t.world[3]);
  view_.origin = choose_world_origin(eye_world, cam.near_plane);
  const glm::dvec3 eye = eye_world - view_.origin;
  glm::mat4 view = cam.view;
  if (view_.origin != glm::dvec3(0.0) || scene_->origin != glm::dvec3(0.0)) {
    const glm::dmat3 rotation{glm::mat3(cam.view)};
    view[3] = glm::vec4(glm::vec3(-(rotation * eye)), 1.0f);
  }
  deformer_->update(scene_->registry, *geometry_, uint32_t(next_frame_ % frames_in_flight_));
  build_draw_list();
  view_.view = view;
  view_.projection = cam.projection;
  view_.view_projection = cam.projection * view;
  view_.inverse_view_projection = glm::inverse(view_.view_projection);
  view_.camera_position = glm::vec3(eye);
  view_.near_plane = cam.near_plane;
  view_.far_plane = cam.far_plane;
  view_.vertical_fov = cam.vertical_fov;
  view_.extent = extent_;
  view_.frame_index = next_frame_;
  if (scene_->light.valid() && scene_->registry.has<DirectionalLight>(scene_->light)) {
    const auto& light = scene_->registry.get<DirectionalLight>(scene_->light);
    view_.light_direction = glm::normalize(light.direction);
    view_.light_radiance = light.color * light.intensity;
    view_.light_angular_diameter_degrees = light.angular_diameter_degrees;
  }
  gather_local_lights();

  gpu_shared::FrameUniforms u{};
  u.view = view_.view;
  u.projection = view_.projection;
  u.view_projection = view_.view_projection;
  u.inverse_view_projection = view_.inverse_view_projection;
  u.camera_position = glm::vec4(view_.camera_position, 1.0f);
  u.light_direction = glm::vec4(view_.light_direction, 0.0f);
  u.light_radiance = glm::vec4(view_.light_radiance, 0.0f);
  u.ambient = glm::vec4(scene_->sky_color, scene_->sky_brightness);
  for (size_t i = 0; i < view_.local_lights.size(); ++i) {
    const FrameLight& l = view_.local_lights[i];
    gpu_shared::LocalLightUniforms& out = u.local_lights[i];
    out.position_range = glm::vec4(l.position, l.range);
    out.direction_kind = glm::vec4(l.direction, l.kind == LocalLightKind::Point ? 1.0f : 0.0f);
    out.radiance = glm::vec4(l.radiance, 0.0f);
    out.cone = glm::vec4(std::cos(l.outer_cone), std::cos(l.inner_cone), 0.0f, 0.0f);
  }
  u.local_light_count = glm::uvec4(uint32_t(view_.local_lights.size()), 0u, 0u, 0u);
  u.extent = glm::uvec4(extent_.width, extent_.height, uint32_t(view_.frame_index),
                        smooth_terminator_ ? gpu_shared::FRAME_FLAG_SMOOTH_TERMINATOR : 0u);
  // The host waited for the frame that last used this slot (frames_in_flight frames ago).
  frame_uniforms_[view_.frame_index % frames_in_flight_].write(&u, sizeof(u));
}

void Renderer::record(VkCommandBuffer cmd) {
  profiler_.begin_frame(cmd);
  try {
    record_frame(cmd);
  } catch (...) {
    // Nothing of this frame will be submitted: it must not be waited for as pending.
    profiler_.cancel_frame();
    throw;
  }
  pending_.push_back(view_.frame_index);
  next_frame_ = view_.frame_index + 1;
}

void Renderer::record_frame(VkCommandBuffer cmd) {
  const gpu::Buffer& frame_uniforms = frame_uniforms_[view_.frame_index % frames_in_flight_];
  {
    ScopedGpuRegion total(ctx_, profiler_, cmd, "frame");
    deformer_->record(cmd, profiler_, *geometry_, uint32_t(view_.frame_index % frames_in_flight_));
    // G-buffer.
    {
      ScopedGpuRegion region(ctx_, profiler_, cmd, "gbuffer");
      VkRenderingAttachmentInfo colors[4];
      Image* targets[4] = {&gbuffer_.albedo, &gbuffer_.normal, &gbuffer_.geometric_normal, &gbuffer_.terminator_offset};
      for (int i = 0; i < 4; ++i) {
        colors[i] = {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
        colors[i].imageView = targets[i]->view();
        colors[i].imageLayout = VK_IMAGE_LAYOUT_GENERAL;
        colors[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        colors[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        colors[i].clearValue.color = {{0.0f, 0.0f, 0.0f, 0.0f}};
      }
      VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
      depth.imageView = gbuffer_.depth.view();
      depth.imageLayout = VK_IMAGE_LAYOUT_GENERAL;
      depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
      depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
      depth.clearValue.depthStencil = {0.0f, 0};  // reversed Z: 0 is the far plane
      VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
      info.renderArea = {{0, 0}, extent_};
      info.layerCount = 1;
      info.colorAttachmentCount = 4;
      info.pColorAttachments = colors;
      info.pDepthAttachment = &depth;
      vkCmdBeginRendering(cmd, &info);
      VkViewport viewport{0, 0, float(extent_.width), float(extent_.height), 0.0f, 1.0f};
      VkRect2D scissor{{0, 0}, extent_};
      vkCmdSetViewport(cmd, 0, 1, &viewport);
      vkCmdSetScissor(cmd, 0, 1, &scissor);
      gbuffer_pipeline_.bind(cmd);
      DescriptorWriter()
          .uniform_buffer(gpu_shared::GBUFFER_BINDING_FRAME, frame_uniforms.handle())
          .storage_buffer(gpu_shared::GBUFFER_BINDING_VERTICES, geometry_->vertices().handle())
          .storage_buffer(gpu_shared::GBUFFER_BINDING_INDICES, geometry_->indices().handle())
          .storage_buffer(gpu_shared::GBUFFER_BINDING_TEXTURES, geometry_->textures().handle())
          .push(ctx_, cmd, gbuffer_pipeline_);
      for (const auto& d : draws_) {
        const auto& range = geometry_->mesh(d.mesh);
        if (range.index_count == 0) continue;
        // Off-screen meshes cost a CPU rasterizer their whole vertex and setup work.
        if (d.bounds.outside_clip(view_.view_projection, glm::vec4(-1.0f, -1.0f, 1.0f, 1.0f), 0.0f)) continue;
        gpu_shared::DrawPush push{};
        push.model = d.world;
        push.base_color = d.base_color;
        push.first_index = range.first_index;
        push.vertex_offset = range.vertex_offset;
        push.flags = d.shadow.receives_shadow ? gpu_shared::DRAW_FLAG_RECEIVES_SHADOW : 0u;
        push.alpha_threshold = d.alpha_threshold;
        push.base_color_texture = d.base_color_texture;
        gbuffer_pipeline_.push_constants(cmd, push);
        vkCmdDraw(cmd, range.index_count, 1, 0, 0);
      }
      vkCmdEndRendering(cmd);
    }
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, kAllStages,
                   kAllAccess);
    // World positions from depth, exactly as every shadow pass and the reference will read them.
    {
      ScopedGpuRegion region(ctx_, profiler_, cmd, "shading_points");
      shading_points_pipeline_.bind(cmd);
      DescriptorWriter()
          .uniform_buffer(gpu_shared::SHADING_POINTS_BINDING_FRAME, frame_uniforms.handle())
          .sampled_image(gpu_shared::SHADING_POINTS_BINDING_DEPTH, gbuffer_.depth.view(), nearest_sampler_.handle(),
                         VK_IMAGE_LAYOUT_GENERAL)
          .storage_image(gpu_shared::SHADING_POINTS_BINDING_WORLD_POSITION, gbuffer_.world_position.view())
          .storage_image(gpu_shared::SHADING_POINTS_BINDING_TERMINATOR_OFFSET, gbuffer_.terminator_offset.view())
          .push(ctx_, cmd, shading_points_pipeline_);
      vkCmdDispatch(cmd, groups(extent_.width, 8), groups(extent_.height, 8), 1);
    }
    // The shading points' writes before the features' and lighting's reads.
    full_barrier(cmd);
    uint32_t written = 0;
    if (use_external_shadow_) {
      VkBufferImageCopy copy{};
      copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
      copy.imageExtent = {extent_.width, extent_.height, 1};
      vkCmdCopyBufferToImage(cmd, external_shadow_.handle(), shadow_term_.handle(), VK_IMAGE_LAYOUT_GENERAL, 1, &copy);
      // The copy before lighting's storage reads.
      memory_barrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
      written = FrameContext::kWroteSunTerm;
    } else {
      FrameContext frame{ctx_,     cmd,           profiler_,      view_,      gbuffer_, shadow_term_,
                         local_shadow_terms_.data(), overlay_, frame_uniforms, *geometry_, draws_, scene_->registry};
      for (auto& f : features_) {
        f->record(frame);
        full_barrier(cmd);
      }
      written = frame.written;
    }
    rest_unwritten(cmd, written);

    {
      ScopedGpuRegion region(ctx_, profiler_, cmd, "lighting");
      const bool local = !view_.local_lights.empty();
      const Pipeline& lighting = local ? local_lighting_pipeline_ : lighting_pipeline_;
      lighting.bind(cmd);
      DescriptorWriter writer;
      writer.uniform_buffer(gpu_shared::LIGHTING_BINDING_FRAME, frame_uniforms.handle())
          .storage_image(gpu_shared::LIGHTING_BINDING_ALBEDO, gbuffer_.albedo.view())
          .storage_image(gpu_shared::LIGHTING_BINDING_NORMAL, gbuffer_.normal.view())
          .storage_image(gpu_shared::LIGHTING_BINDING_WORLD_POSITION, gbuffer_.world_position.view())
          .storage_image(gpu_shared::LIGHTING_BINDING_SHADOW, shadow_term_.view())
          .storage_image(gpu_shared::LIGHTING_BINDING_OVERLAY, overlay_.view())
          .storage_image(gpu_shared::LIGHTING_BINDING_OUTPUT, output_.view());
      if (local)
        for (uint32_t i = 0; i < kMaxLocalLights; ++i)
          writer.storage_image(gpu_shared::LIGHTING_BINDING_LOCAL_SHADOW + i, local_shadow_terms_[i].view());
      writer.push(ctx_, cmd, lighting);
      vkCmdDispatch(cmd, groups(extent_.width, 8), groups(extent_.height, 8), 1);
    }
    full_barrier(cmd);
  }
}

// The sun's term and each local light's to 1 (lit), the overlay to 0, where no feature wrote them
// this frame and they do not hold those values already; ordered before lighting's reads. On a GPU
// that clears storage images through its graphics units (an H200: 0.6 ms for a 4K R32F image) the
// clears a feature overwrites anyway were most of a frame's fixed cost.
void Renderer::rest_unwritten(VkCommandBuffer cmd, uint32_t written) {
  const VkClearColorValue one{{1.0f, 1.0f, 1.0f, 1.0f}}, zero{{0.0f, 0.0f, 0.0f, 0.0f}};
  const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  bool cleared = false;
  auto rest = [&](Image& image, uint32_t bit, const VkClearColorValue& value) {
    if (written & bit) {
      at_rest_ &= ~bit;
    } else if (!(at_rest_ & bit)) {
      vkCmdClearColorImage(cmd, image.handle(), VK_IMAGE_LAYOUT_GENERAL, &value, 1, &range);
      at_rest_ |= bit;
      cleared = true;
    }
  };
  rest(shadow_term_, FrameContext::kWroteSunTerm, one);
  rest(overlay_, FrameContext::kWroteOverlay, zero);
  for (size_t i = 0; i < view_.local_lights.size(); ++i)
    rest(local_shadow_terms_[i], FrameContext::kWroteLocalTerm << i, one);
  // The clears (transfer writes) before lighting's storage reads.
  if (cleared)
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

void Renderer::after_frame() {
  if (pending_.empty()) return;
  completed_frame_ = pending_.front();
  pending_.pop_front();
  profiler_.collect();
  for (auto& f : features_) f->after_frame(ctx_);
}

void Renderer::finish_frames() {
  vkDeviceWaitIdle(ctx_.device());
  while (!pending_.empty()) after_frame();
}

void Renderer::render_frame(float dt) {
  update(dt);
  ctx_.record_submit_wait(frame_cmd_, frame_fence_, [&](VkCommandBuffer cmd) { record(cmd); });
  after_frame();
}

void Renderer::set_external_shadow_term(std::vector<float> term) {
  if (term.empty()) {
    use_external_shadow_ = false;
    return;
  }
  if (term.size() != size_t(extent_.width) * extent_.height)
    throw std::invalid_argument("external shadow term has the wrong size");
  for (float& v : term) v = v < 0.0f ? 1.0f : v;  // background pixels: unshadowed
  // A frame in flight may still copy from the buffer being replaced.
  if (!pending_.empty()) vkDeviceWaitIdle(ctx_.device());
  external_shadow_ = Buffer(ctx_, term.size() * sizeof(float), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true,
                            "external shadow term");
  external_shadow_.write(term.data(), term.size() * sizeof(float));
  use_external_shadow_ = true;
}

std::vector<uint8_t> Renderer::read_output_rgba8() { return read_image(ctx_, output_, 4); }

std::vector<glm::vec4> Renderer::read_world_positions() { return read_image_as<glm::vec4>(ctx_, gbuffer_.world_position); }

std::vector<glm::vec4> Renderer::read_geometric_normals() {
  // RGBA16F on the GPU; widened here.
  Image wide(ctx_, extent_, VK_FORMAT_R32G32B32A32_SFLOAT,
             VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, "normal readback");
  ctx_.immediate_submit([&](VkCommandBuffer cmd) {
    wide.transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                    VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    memory_barrier(cmd, kAllStages, kAllAccess, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkImageBlit blit{};
    blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {int32_t(extent_.width), int32_t(extent_.height), 1};
    blit.dstOffsets[1] = {int32_t(extent_.width), int32_t(extent_.height), 1};
    vkCmdBlitImage(cmd, gbuffer_.geometric_normal.handle(), VK_IMAGE_LAYOUT_GENERAL, wide.handle(),
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_NEAREST);
    wide.transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
  });
  return read_image_as<glm::vec4>(ctx_, wide);
}

std::vector<float> Renderer::read_depth() { return read_image_as<float>(ctx_, gbuffer_.depth); }

std::vector<float> Renderer::read_shadow_term() { return read_image_as<float>(ctx_, shadow_term_); }
std::vector<float> Renderer::read_local_shadow_term(uint32_t i) {
  return read_image_as<float>(ctx_, local_shadow_terms_.at(i));
}

void write_rgba8_png(const std::filesystem::path& path, uint32_t width, uint32_t height, const uint8_t* rgba) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  if (!stbi_write_png(path.c_str(), int(width), int(height), 4, rgba, int(width * 4)))
    throw std::runtime_error("cannot write PNG " + path.string());
}

void Renderer::write_png(const std::filesystem::path& path) {
  auto pixels = read_output_rgba8();
  write_rgba8_png(path, extent_.width, extent_.height, pixels.data());
}

}  // namespace engine
