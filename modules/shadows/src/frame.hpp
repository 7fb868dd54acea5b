#pragma once
// What every pass records from: the module's own copy of the frame's inputs, made from the host's
// images and instances by the context (context.cpp). No pass sees a host resource.
#include <string>
#include <vector>

#include "scene_types.hpp"
#include "gpu/pipeline.hpp"
#include "gpu/profiler.hpp"
#include "gpu/resources.hpp"

namespace shadows::detail {

struct View {
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};  // reversed Z (the module's convention, whatever the host uses)
  glm::mat4 view_projection{1.0f};
  glm::mat4 inverse_view_projection{1.0f};  // NDC (y down, reversed depth) -> world
  glm::vec3 camera_position{0.0f};
  glm::vec3 light_direction{0.0f, -1.0f, 0.0f};  // travel direction, unit (directional and spot)
  bool local_light = false;        // a spot or point light (else the sun)
  glm::vec3 light_position{0.0f};  // spot and point
  float light_range = 0.0f;        // spot and point
  float light_cos_outer = -1.0f;   // spot: cosine of the outer cone; point: -1 (every direction)
  bool light_face = false;         // one of a point light's six faces, shadowed as a spot light (IZB)
  uint32_t light_face_index = 0;   // which: +x, -x, +y, -y, +z, -z (the order they are recorded in)
  // This face's place among the light's faces recorded this frame (0 the first), and whether it is
  // the last (a face whose cone no visible point lies in is skipped: cone_may_reach_view).
  uint32_t light_face_order = 0;
  bool last_light_face = true;
  bool first_light_face() const { return light_face_order == 0; }
  // The light's size (Light::angular_diameter_degrees, radius): the sun's tangent of its angular
  // radius; a spot or point light's sphere radius in world units. 0: a point, hard shadows.
  float light_tan_half_angle = 0.0f;
  float light_radius = 0.0f;
  float near_plane = 0.05f;
  float far_plane = 200.0f;
  glm::vec2 tan_half_fov{1.0f};  // x, y: tangent of the half field of view (from the projection)
  VkExtent2D extent{};
  uint64_t frame_index = 0;
};

// The per-pixel inputs every pass reads as storage images in GENERAL layout: the module's own, written
// by its input pass, or the host's native ones (FrameDesc::native) read in place.
struct ShadingInputs {
  VkImageView world_position = VK_NULL_HANDLE;    // RGBA32F: shading point; w = 1 covered, 0 background
  VkImageView geometric_normal = VK_NULL_HANDLE;  // RGBA16F: unit normal facing the camera; w = faces the light
  VkImageView albedo = VK_NULL_HANDLE;            // RGBA8: a = receives shadows (rgb unused)
};

// One caster mesh in the module's vertex and index buffers.
struct MeshRange {
  uint32_t first_index = 0;
  uint32_t index_count = 0;
  int32_t vertex_offset = 0;
  uint32_t vertex_count = 0;
  // A deformed slot (GeometryStore): a registered mesh's indices over vertices of its own, whose
  // positions a deformed instance rewrites every frame it is drawn (Instance::deformed).
  bool deformed = false;
};

// Every registered mesh in one vertex buffer (StoredVertex: position, normal, uv) and one
// 32-bit index buffer, plus the alpha textures in the material-texture word layout (shared/material.h).
// The mesh table holds the registered meshes' ranges and, among them in order of creation, the
// deformed slots' (MeshRange::deformed); a DrawItem names its entry.
class Geometry {
 public:
  const engine::gpu::Buffer& vertices() const { return vertices_; }
  const engine::gpu::Buffer& indices() const { return indices_; }
  const engine::gpu::Buffer& textures() const { return textures_; }
  const MeshRange& mesh(uint32_t entry) const { return meshes_.at(entry); }
  size_t mesh_count() const { return meshes_.size(); }  // table entries: meshes and deformed slots

 private:
  friend class GeometryStore;
  engine::gpu::Buffer vertices_;
  engine::gpu::Buffer indices_;
  engine::gpu::Buffer textures_;
  std::vector<MeshRange> meshes_;
};

// One caster instance this frame.
struct DrawItem {
  uint64_t id = 0;  // the host's Instance::id
  std::string name;
  glm::mat4 world{1.0f};
  uint32_t mesh = 0;                          // Geometry mesh table entry (a deformed slot for a deformed instance)
  uint32_t alpha_threshold = 0;               // engine::alpha_threshold (0: not alpha-tested)
  uint32_t base_color_texture = 0xffffffffu;  // texture index in Geometry::textures(), or none
  bool alpha_tested() const { return alpha_threshold != 0; }
  CasterFlags shadow;
  Aabb bounds;  // world space (invalid: unbounded)
};

// The last conservative shadow map, for tests and tools.
struct CsmSnapshot {
  uint32_t resolution = 0;
  std::vector<float> depth;  // row-major, resolution^2, 1 = nothing stored
  glm::mat4 light_view_projection{1.0f};
};

// The last lit map (IzbSettings::lit_culling), for tests and tools: per texel a depth no farther from
// the light than any caster touching it (+infinity where none does).
struct LitMapSnapshot {
  uint32_t resolution = 0;
  std::vector<float> depth;         // row-major, resolution^2
  std::vector<float> corner_depth;  // the texels' corners' plane bounds, row-major, (resolution + 1)^2
  // The tile level (izb_common.glsl, lit_tile_record): casters covering a whole tile of `tile`^2
  // texels are bounded there, not at its texels.
  uint32_t tile = 0, tiles_per_side = 0;
  std::vector<float> tile_depth;         // row-major, tiles_per_side^2
  // Each tile's own four corners' plane bounds (c00, c10, c01, c11 at the tile's corners (x, y),
  // (x + 1, y), (x, y + 1), (x + 1, y + 1); corner i at grid min(i * tile, resolution)), 4 a tile.
  std::vector<float> tile_corner_depth;
  std::vector<float> tile_least_depth;   // row-major, tiles_per_side^2: no farther than any of the tile's texels' `depth`
  glm::mat4 light_view_projection{1.0f};
};

// The image a light's passes write its term into: the module's own, or the host's output where the
// output pass would only copy it (ContextImpl::term_target).
struct TermImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView image_view = VK_NULL_HANDLE;
  VkImage handle() const { return image; }
  VkImageView view() const { return image_view; }
};

struct Frame {
  engine::gpu::Context& ctx;
  VkCommandBuffer cmd;
  engine::gpu::GpuProfiler& profiler;
  const View& view;
  const ShadingInputs& gbuffer;
  TermImage shadow_term;            // R32F storage, GENERAL, 1 (lit) where no technique writes
  engine::gpu::Image& overlay;      // RGBA8 storage, GENERAL; cleared to 0 only when a debug view is on
  Geometry& geometry;
  const std::vector<DrawItem>& draws;
  uint32_t slot = 0;   // frame-in-flight slot of this frame
  uint32_t slots = 1;  // frames in flight
};

// Host-visible copies of a GPU buffer, one per frame in flight: a frame copies into its slot's copy,
// which is read once that frame has completed, so frames in flight never share a readback.
class ReadbackRing {
 public:
  // After `writers` / `writes` (the stages and accesses that produced `source`), copies `bytes` of it
  // into a host-visible copy of the frame's and makes that visible to the host. A frame may record
  // several copies (one per light): each gets its own. A copy may hold `records` records of
  // bytes / records bytes each (a point light's faces' counters, copied at once).
  void record_copy(const Frame& frame, const engine::gpu::Buffer& source, VkDeviceSize bytes,
                   VkPipelineStageFlags2 writers, VkAccessFlags2 writes, const char* name, uint32_t records = 1) {
    if (slots_.size() != frame.slots) {
      slots_.clear();
      slots_.resize(frame.slots);
    }
    Slot& slot = slots_[frame.slot];
    if (slot.count == 0 || slot.frame != frame.view.frame_index) {
      slot.count = 0;
      slot.frame = frame.view.frame_index;
    }
    if (slot.copies.size() <= slot.count) slot.copies.emplace_back();
    Copy& copy = slot.copies[slot.count++];
    copy.records = records;
    if (!copy.buffer.valid() || copy.buffer.size() < bytes)
      copy.buffer = engine::gpu::Buffer(frame.ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true, name);
    copy.stride = bytes / records;
    engine::gpu::memory_barrier(frame.cmd, writers, writes, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    const VkBufferCopy region{0, 0, bytes};
    vkCmdCopyBuffer(frame.cmd, source.handle(), copy.buffer.handle(), 1, &region);
    engine::gpu::memory_barrier(frame.cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  }
  // How many records the slot's frame `frame_index` has copied so far.
  uint32_t recorded(uint32_t slot, uint64_t frame_index) const {
    if (slot >= slots_.size() || slots_[slot].frame != frame_index) return 0u;
    uint32_t records = 0;
    for (uint32_t i = 0; i < slots_[slot].count; ++i) records += slots_[slot].copies[i].records;
    return records;
  }
  // The slot's records, in the order its frame copied them, when not taken yet; else none.
  std::vector<const void*> take_records(uint32_t slot) {
    std::vector<const void*> out;
    if (slot >= slots_.size()) return out;
    for (uint32_t i = 0; i < slots_[slot].count; ++i) {
      const Copy& copy = slots_[slot].copies[i];
      for (uint32_t r = 0; r < copy.records; ++r) out.push_back(copy.buffer.as<uint8_t>() + r * copy.stride);
    }
    slots_[slot].count = 0;
    return out;
  }
  // The last copy of the slot's frame, when not taken yet; else null.
  const engine::gpu::Buffer* take(uint32_t slot) {
    if (slot >= slots_.size() || slots_[slot].count == 0) return nullptr;
    const engine::gpu::Buffer* last = &slots_[slot].copies[slots_[slot].count - 1].buffer;
    slots_[slot].count = 0;
    return last;
  }

 private:
  struct Copy {
    engine::gpu::Buffer buffer;
    uint32_t records = 1;
    VkDeviceSize stride = 0;
  };
  struct Slot {
    std::vector<Copy> copies;
    uint32_t count = 0;  // copies recorded and not taken
    uint64_t frame = 0;
  };
  std::vector<Slot> slots_;
};

}  // namespace shadows::detail
