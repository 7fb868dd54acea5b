#include "geometry_store.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <shared/host.h>
#include <shared/material.h>

#include "barriers.hpp"
#include "input_checks.hpp"

namespace shadows::detail {

using engine::gpu::Buffer;
using engine::gpu::DescriptorWriter;
using engine::gpu::memory_barrier;

namespace {

// Header words reserved for textures (shared/material.h: count, then 4 words each); texels follow.
constexpr uint32_t kMaxTextures = 1024;
constexpr uint32_t kTexelBase = 1 + gpu_shared::kTextureHeaderWords * kMaxTextures;

constexpr VkAccessFlags2 kGeometryReads = VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_2_INDEX_READ_BIT |
                                          VK_ACCESS_2_SHADER_STORAGE_READ_BIT;

}  // namespace

// Every stage that reads the module's geometry on this device: vertex fetch and shader storage reads
// of the raster and compute passes, and acceleration-structure builds where ray tracing is on.
VkPipelineStageFlags2 GeometryStore::geometry_readers() const {
  VkPipelineStageFlags2 stages = pass_shader_stages(*ctx_) | VK_PIPELINE_STAGE_2_VERTEX_INPUT_BIT;
  if (ctx_->features().acceleration_structure) stages |= VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR;
  return stages;
}

void GeometryStore::init(engine::gpu::Context& ctx, bool ray_tracing) {
  ctx_ = &ctx;
  geometry_usage_ = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                    VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  if (ray_tracing)
    geometry_usage_ |= VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                       VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  using engine::gpu::Binding;
  import_ = engine::gpu::PipelineFactory(ctx).compute(
      {.shader = "mesh_import.comp",
       .bindings = {{gpu_shared::MESH_IMPORT_BINDING_SOURCE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                    {gpu_shared::MESH_IMPORT_BINDING_UVS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                    {gpu_shared::MESH_IMPORT_BINDING_VERTICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                    {gpu_shared::MESH_IMPORT_BINDING_INDICES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                    {gpu_shared::MESH_IMPORT_BINDING_BOUNDS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
       .push_constant_size = sizeof(gpu_shared::MeshImportPush)});
  bounds_ = Buffer(ctx, 6 * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "shadows mesh bounds readback");
  texture_import_ = engine::gpu::PipelineFactory(ctx).compute(
      {.shader = "texture_import.comp",
       .bindings = {{gpu_shared::TEXTURE_IMPORT_BINDING_SOURCE, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                    {gpu_shared::TEXTURE_IMPORT_BINDING_WORDS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
       .push_constant_size = sizeof(gpu_shared::TextureImportPush)});
  nearest_ = engine::gpu::Sampler(ctx, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "shadows nearest");
  // Placeholders so every binding is valid before the first mesh arrives.
  geometry_.vertices_ = Buffer(ctx, 32 * 3, geometry_usage_ | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, false, "shadows vertices");
  geometry_.indices_ = Buffer(ctx, 4 * 3, geometry_usage_ | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, false, "shadows indices");
  geometry_.textures_ = Buffer(ctx, kTexelBase * 4, geometry_usage_, false, "shadows alpha textures");
}

MeshId GeometryStore::add(const MeshDesc& m) {
  const std::string what = "MeshDesc '" + m.name + "'";
  if (m.index_count == 0 || m.index_count % 3 != 0)
    throw Error("shadows: " + what + ".index_count is " + std::to_string(m.index_count) +
                " (a mesh needs a positive multiple of 3)");
  if (m.vertex_count == 0) throw Error("shadows: " + what + ".vertex_count is 0");
  if (m.position_format != VK_FORMAT_R32G32B32_SFLOAT && m.position_format != VK_FORMAT_R32G32B32A32_SFLOAT)
    throw Error("shadows: " + what + ".position_format must be VK_FORMAT_R32G32B32_SFLOAT or R32G32B32A32_SFLOAT");
  const uint32_t position_bytes = m.position_format == VK_FORMAT_R32G32B32_SFLOAT ? 12 : 16;
  if (m.position_stride < position_bytes || m.position_stride % 4)
    throw Error("shadows: " + what + ".position_stride " + std::to_string(m.position_stride) +
                " must be a multiple of 4 of at least " + std::to_string(position_bytes));
  check_buffer(m.positions, what + ".positions",
               VkDeviceSize(m.vertex_count - 1) * m.position_stride + position_bytes);
  if (m.index_type != VK_INDEX_TYPE_UINT16 && m.index_type != VK_INDEX_TYPE_UINT32)
    throw Error("shadows: " + what + ".index_type must be VK_INDEX_TYPE_UINT16 or VK_INDEX_TYPE_UINT32");
  const uint32_t index_bytes = m.index_type == VK_INDEX_TYPE_UINT16 ? 2 : 4;
  // 16-bit indices are read as whole 4-byte words: the region must reach the end of the last word.
  const VkDeviceSize index_end = m.indices.offset + VkDeviceSize(m.index_count) * index_bytes;
  check_buffer(m.indices, what + ".indices", (index_end + 3) / 4 * 4 - m.indices.offset, index_bytes == 2);
  MeshInfo info;
  info.name = m.name;
  if (m.alpha_texture.present()) {
    if (m.uvs.buffer == VK_NULL_HANDLE) throw Error("shadows: " + what + ".uvs is required with an alpha_texture");
    if (m.uv_stride < 8 || m.uv_stride % 4)
      throw Error("shadows: " + what + ".uv_stride must be a multiple of 4 of at least 8");
    check_buffer(m.uvs, what + ".uvs", VkDeviceSize(m.vertex_count - 1) * m.uv_stride + 8);
    check_image(m.alpha_texture, what + ".alpha_texture",
                {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8_UNORM},
                VK_IMAGE_USAGE_SAMPLED_BIT, kReadLayouts, std::nullopt);
    if (texture_count_ >= kMaxTextures)
      throw Error("shadows: " + what + ".alpha_texture: more than " + std::to_string(kMaxTextures) + " alpha textures");
    info.alpha_threshold = gpu_shared::alpha_threshold_byte(m.alpha_cutoff, m.alpha_scale);
    info.texture = texture_count_;
  }
  if (m.bounds) {
    const MeshBounds& b = *m.bounds;
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(b.min[c]) || !std::isfinite(b.max[c]))
        throw Error("shadows: " + what + ".bounds has a value that is not finite");
    if (!(b.min[0] <= b.max[0] && b.min[1] <= b.max[1] && b.min[2] <= b.max[2]))
      throw Error("shadows: " + what + ".bounds is not a box (min <= max on every axis)");
    info.bounds.extend(glm::vec3(b.min[0], b.min[1], b.min[2]));
    info.bounds.extend(glm::vec3(b.max[0], b.max[1], b.max[2]));
  } else {
    // Last: every other field is checked before anything is submitted.
    info.bounds = device_bounds(m, what);
  }
  info.live = true;
  info.vertex_count = m.vertex_count;
  info.entry = uint32_t(geometry_.meshes_.size());
  if (m.alpha_texture.present()) ++texture_count_;  // only once nothing can refuse the mesh
  const MeshId id = MeshId(meshes_.size());
  MeshRange range;
  range.first_index = index_count_;
  range.index_count = m.index_count;
  range.vertex_offset = int32_t(vertex_count_);
  range.vertex_count = m.vertex_count;
  index_count_ += m.index_count;
  vertex_count_ += m.vertex_count;
  Pending pending{id, m, 0};
  if (m.alpha_texture.present()) {
    pending.texture_first_word = kTexelBase + texel_words_;
    texel_words_ += m.alpha_texture.extent.width * m.alpha_texture.extent.height;
  }
  meshes_.push_back(std::move(info));
  geometry_.meshes_.push_back(range);
  pending_.push_back(std::move(pending));
  return id;
}

void GeometryStore::remove(MeshId id) {
  if (id >= meshes_.size() || !meshes_[id].live)
    throw Error("shadows: unregister_mesh: mesh id " + std::to_string(id) + " is not registered");
  meshes_[id].live = false;
  // Not yet imported: nothing will read the host's buffers.
  std::erase_if(pending_, [&](const Pending& p) { return p.id == id; });
}

std::pair<VkDeviceSize, VkDeviceSize> GeometryStore::bind_region(const BufferInput& in, uint32_t& word) const {
  const VkDeviceSize alignment = ctx_->properties().limits.minStorageBufferOffsetAlignment;
  const VkDeviceSize base = in.offset / alignment * alignment;
  word = uint32_t((in.offset - base) / 4);
  return {base, in.offset - base + in.size};
}

// Binds a host positions region as the import pass's source (and, unread, as its uvs) and returns the
// push of a pass reading `count` positions `stride` bytes apart from it in `mode` (no uvs).
gpu_shared::MeshImportPush GeometryStore::bind_positions(VkCommandBuffer cmd, const BufferInput& in, uint32_t stride,
                                                         uint32_t count, uint32_t mode) {
  uint32_t position_word = 0;
  const auto [base, range] = bind_region(in, position_word);
  push_import_buffers(cmd, in.buffer, base, range, in.buffer, base, range);
  gpu_shared::MeshImportPush push{};
  push.mode = mode;
  push.src_word = position_word;
  push.stride_words = stride / 4;
  push.count = count;
  push.uv_word = gpu_shared::kNoUv;
  return push;
}

// The positions' min and max, by the import shader's MESH_IMPORT_BOUNDS pass on the adopted queue,
// waited for and read back (MeshDesc::bounds documents the cost and what the host must guarantee).
Aabb GeometryStore::device_bounds(const MeshDesc& m, const std::string& what) {
  uint32_t* keys = bounds_.as<uint32_t>();
  for (int c = 0; c < 3; ++c) keys[c] = gpu_shared::kMeshBoundsEmptyMin, keys[3 + c] = gpu_shared::kMeshBoundsEmptyMax;
  ctx_->immediate_submit([&](VkCommandBuffer cmd) {
    // Earlier work on this queue (the host's uploads of the positions, frames binding the readback)
    // finishes its writes before the pass reads and writes.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                   VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                   VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    import_.bind(cmd);
    const gpu_shared::MeshImportPush push =
        bind_positions(cmd, m.positions, m.position_stride, m.vertex_count, gpu_shared::MESH_IMPORT_BOUNDS);
    import_.push_constants(cmd, push);
    vkCmdDispatch(cmd, groups(m.vertex_count, 64), 1, 1);
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  });
  float values[6];
  for (int k = 0; k < 6; ++k) {
    const uint32_t bits = gpu_shared::mesh_bounds_float_bits(keys[k]);
    std::memcpy(&values[k], &bits, 4);
    if (!std::isfinite(values[k]))
      throw Error("shadows: " + what + ".positions hold a value that is not finite (bounds absent, computed from them)");
  }
  Aabb box;
  box.min = glm::vec3(values[0], values[1], values[2]);
  box.max = glm::vec3(values[3], values[4], values[5]);
  return box;
}

void GeometryStore::push_import_buffers(VkCommandBuffer cmd, VkBuffer source, VkDeviceSize base, VkDeviceSize range,
                                        VkBuffer uvs, VkDeviceSize uv_base, VkDeviceSize uv_range) {
  DescriptorWriter()
      .storage_buffer(gpu_shared::MESH_IMPORT_BINDING_SOURCE, source, base, range)
      .storage_buffer(gpu_shared::MESH_IMPORT_BINDING_UVS, uvs, uv_base, uv_range)
      .storage_buffer(gpu_shared::MESH_IMPORT_BINDING_VERTICES, geometry_.vertices_.handle())
      .storage_buffer(gpu_shared::MESH_IMPORT_BINDING_INDICES, geometry_.indices_.handle())
      .storage_buffer(gpu_shared::MESH_IMPORT_BINDING_BOUNDS, bounds_.handle())
      .push(*ctx_, cmd, import_);
}

const MeshInfo* GeometryStore::find(MeshId id) const {
  return id < meshes_.size() && meshes_[id].live ? &meshes_[id] : nullptr;
}

void GeometryStore::grow(Buffer& buffer, VkDeviceSize bytes, VkDeviceSize used, VkBufferUsageFlags usage,
                         const char* name, VkCommandBuffer cmd) {
  if (buffer.valid() && buffer.size() >= bytes) return;
  Buffer grown(*ctx_, std::max(bytes, buffer.size() * 2), usage, false, name);
  if (used > 0) {
    // Earlier frames' readers of the old buffer are ordered before the copy by the barrier that
    // opened this frame's imports; the copy's write is made visible with the imports' own.
    const VkBufferCopy copy{0, 0, used};
    vkCmdCopyBuffer(cmd, buffer.handle(), grown.handle(), 1, &copy);
  }
  buffer = std::move(grown);  // the old one is released once the frames that used it completed
}

// The vertex, index and texture buffers grown to hold the pending meshes, what earlier meshes stored
// copied over.
void GeometryStore::grow_for_pending(VkCommandBuffer cmd) {
  uint32_t first_pending_vertex = UINT32_MAX, first_pending_index = UINT32_MAX;
  for (const auto& p : pending_) {
    const MeshRange& range = geometry_.meshes_[meshes_[p.id].entry];
    first_pending_vertex = std::min(first_pending_vertex, uint32_t(range.vertex_offset));
    first_pending_index = std::min(first_pending_index, range.first_index);
  }
  grow(geometry_.vertices_, VkDeviceSize(vertex_count_) * 32, VkDeviceSize(first_pending_vertex) * 32,
       geometry_usage_ | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "shadows vertices", cmd);
  grow(geometry_.indices_, VkDeviceSize(index_count_) * 4, VkDeviceSize(first_pending_index) * 4,
       geometry_usage_ | VK_BUFFER_USAGE_INDEX_BUFFER_BIT, "shadows indices", cmd);
  const VkDeviceSize texture_bytes = VkDeviceSize(kTexelBase + texel_words_) * 4;
  const VkDeviceSize textures_used = geometry_.textures_.size();
  grow(geometry_.textures_, texture_bytes, std::min<VkDeviceSize>(textures_used, texture_bytes), geometry_usage_,
       "shadows alpha textures", cmd);
}

// One pending mesh's positions, uvs and indices into the module's buffers (import_ bound).
void GeometryStore::import_mesh(VkCommandBuffer cmd, const Pending& p) {
  const VkDeviceSize alignment = ctx_->properties().limits.minStorageBufferOffsetAlignment;
  const MeshRange& range = geometry_.meshes_[meshes_[p.id].entry];
  const MeshDesc& m = p.desc;
  gpu_shared::MeshImportPush push{};
  uint32_t position_word = 0, uv_word = 0;
  const auto [pos_base, pos_range] = bind_region(m.positions, position_word);
  push.uv_word = gpu_shared::kNoUv;
  if (m.uvs.buffer != VK_NULL_HANDLE) {
    const auto [uv_base, uv_range] = bind_region(m.uvs, uv_word);
    push_import_buffers(cmd, m.positions.buffer, pos_base, pos_range, m.uvs.buffer, uv_base, uv_range);
    push.uv_word = uv_word;
    push.uv_stride_words = m.uv_stride / 4;
  } else {
    push_import_buffers(cmd, m.positions.buffer, pos_base, pos_range, m.positions.buffer, pos_base, pos_range);
  }
  push.mode = gpu_shared::MESH_IMPORT_VERTICES;
  push.src_word = position_word;
  push.stride_words = m.position_stride / 4;
  push.count = m.vertex_count;
  push.dst_first = uint32_t(range.vertex_offset);
  import_.push_constants(cmd, push);
  vkCmdDispatch(cmd, groups(m.vertex_count, 64), 1, 1);

  // Indices: 16-bit ones may start at an odd half-word; the shader takes the half from stride_words.
  const VkDeviceSize index_base = m.indices.offset / alignment * alignment;
  const VkDeviceSize index_delta = m.indices.offset - index_base;
  // Whole words, within the region add() checked (its end rounded down to a word).
  const VkDeviceSize index_range = (index_delta + m.indices.size) / 4 * 4;
  push_import_buffers(cmd, m.indices.buffer, index_base, index_range, m.indices.buffer, index_base, index_range);
  gpu_shared::MeshImportPush ipush{};
  ipush.src_word = uint32_t(index_delta / 4);
  ipush.count = m.index_count;
  ipush.dst_first = range.first_index;
  ipush.uv_word = gpu_shared::kNoUv;
  if (m.index_type == VK_INDEX_TYPE_UINT16) {
    ipush.mode = gpu_shared::MESH_IMPORT_INDICES_16;
    ipush.stride_words = uint32_t((index_delta / 2) & 1u);
  } else {
    ipush.mode = gpu_shared::MESH_IMPORT_INDICES_32;
  }
  import_.push_constants(cmd, ipush);
  vkCmdDispatch(cmd, groups(m.index_count, 64), 1, 1);
}

// The pending meshes' alpha textures: texels by compute, headers and the count by updates.
void GeometryStore::import_textures(VkCommandBuffer cmd) {
  struct Header {
    VkDeviceSize offset;
    uint32_t words[4];
  };
  std::vector<Header> headers;
  texture_import_.bind(cmd);
  for (const auto& p : pending_) {
    const MeshDesc& m = p.desc;
    if (!m.alpha_texture.present()) continue;
    const MeshInfo& info = meshes_[p.id];
    DescriptorWriter()
        .sampled_image(gpu_shared::TEXTURE_IMPORT_BINDING_SOURCE, m.alpha_texture.view, nearest_.handle(),
                       m.alpha_texture.layout)
        .storage_buffer(gpu_shared::TEXTURE_IMPORT_BINDING_WORDS, geometry_.textures_.handle())
        .push(*ctx_, cmd, texture_import_);
    gpu_shared::TextureImportPush push{p.texture_first_word, m.alpha_texture.extent.width,
                                       m.alpha_texture.extent.height, m.alpha_texture.format == VK_FORMAT_R8_UNORM};
    texture_import_.push_constants(cmd, push);
    vkCmdDispatch(cmd, groups(push.width, 8), groups(push.height, 8), 1);
    headers.push_back({VkDeviceSize(1 + 4 * info.texture) * 4,
                       {p.texture_first_word, push.width, push.height, uint32_t(m.wrap_u) | (uint32_t(m.wrap_v) << 8)}});
  }
  // The texel dispatches bind the whole buffer, so the header updates are ordered after them.
  if (!headers.empty())
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  for (const Header& h : headers)
    vkCmdUpdateBuffer(cmd, geometry_.textures_.handle(), h.offset, sizeof(h.words), h.words);
  vkCmdUpdateBuffer(cmd, geometry_.textures_.handle(), 0, 4, &texture_count_);
}

void GeometryStore::record_imports(VkCommandBuffer cmd) {
  if (pending_.empty()) return;
  // Previous frames read these buffers (and may still run): their reads finish before this frame's
  // copies and imports write.
  memory_barrier(cmd, geometry_readers(), 0,
                 VK_PIPELINE_STAGE_2_COPY_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0);
  grow_for_pending(cmd);
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                 VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT);
  import_.bind(cmd);
  for (const auto& p : pending_) import_mesh(cmd, p);
  import_textures(cmd);
  // The imports' writes, visible to every reader of the geometry later in this frame.
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                 VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 geometry_readers(), kGeometryReads);
  pending_.clear();
}

// Each instance's table entry for this frame: a deformed one takes the next slot of its mesh, made
// here where the mesh has no more (its range: the mesh's indices over new vertices at the buffer's end).
uint32_t GeometryStore::assign_entries(const Instance* instances, uint32_t count,
                                       std::vector<std::pair<uint32_t, uint32_t>>& fresh) {
  const uint32_t first_new_vertex = vertex_count_;
  entries_.assign(count, 0);
  std::vector<uint32_t> taken(meshes_.size(), 0);  // deformed instances so far, per mesh
  for (uint32_t i = 0; i < count; ++i) {
    const Instance& in = instances[i];
    MeshInfo& mesh = meshes_[in.mesh];
    if (!in.deformed.present()) {
      entries_[i] = mesh.entry;
      continue;
    }
    uint32_t& k = taken[in.mesh];
    if (k == mesh.deformed_slots.size()) {
      MeshRange slot = geometry_.meshes_[mesh.entry];
      slot.vertex_offset = int32_t(vertex_count_);
      slot.deformed = true;
      vertex_count_ += slot.vertex_count;
      mesh.deformed_slots.push_back(uint32_t(geometry_.meshes_.size()));
      fresh.push_back({mesh.entry, mesh.deformed_slots.back()});
      geometry_.meshes_.push_back(slot);
    }
    entries_[i] = mesh.deformed_slots[k++];
  }
  return first_new_vertex;
}

// One deformed instance's host positions into its slot (import_ bound): positions only, the slot's
// normals and uvs stay those copied from its mesh.
void GeometryStore::import_positions(VkCommandBuffer cmd, const DeformedPositions& in, const MeshRange& slot) {
  gpu_shared::MeshImportPush push =
      bind_positions(cmd, in.positions, in.stride, slot.vertex_count, gpu_shared::MESH_IMPORT_POSITIONS);
  push.dst_first = uint32_t(slot.vertex_offset);
  import_.push_constants(cmd, push);
  vkCmdDispatch(cmd, groups(slot.vertex_count, 64), 1, 1);
}

const std::vector<uint32_t>& GeometryStore::record_deformed(VkCommandBuffer cmd, const Instance* instances,
                                                            uint32_t count) {
  std::vector<std::pair<uint32_t, uint32_t>> fresh;  // (mesh entry, new slot entry)
  const uint32_t first_new_vertex = assign_entries(instances, count, fresh);
  const bool any = std::any_of(instances, instances + count, [](const Instance& in) { return in.deformed.present(); });
  if (!any) return entries_;
  // Every earlier reader of the vertex buffer (this frame's imports' readers to come, and the previous
  // frames' passes on the queue, which read the slots) finishes before the copies and imports write.
  memory_barrier(cmd, geometry_readers() | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                 VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_COPY_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                 VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  if (!fresh.empty()) {
    grow(geometry_.vertices_, VkDeviceSize(vertex_count_) * 32, VkDeviceSize(first_new_vertex) * 32,
         geometry_usage_ | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "shadows vertices", cmd);
    // The grown buffer's copy lands before the new slots copy their meshes' vertices out of it.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                   VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT);
    std::vector<VkBufferCopy> copies;
    for (const auto& [mesh, slot] : fresh) {
      const MeshRange& from = geometry_.meshes_[mesh];
      const MeshRange& to = geometry_.meshes_[slot];
      copies.push_back({VkDeviceSize(from.vertex_offset) * 32, VkDeviceSize(to.vertex_offset) * 32,
                        VkDeviceSize(to.vertex_count) * 32});
    }
    vkCmdCopyBuffer(cmd, geometry_.vertices_.handle(), geometry_.vertices_.handle(), uint32_t(copies.size()),
                    copies.data());
    // The slots' copied vertices are written before the imports overwrite their positions.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  }
  import_.bind(cmd);
  for (uint32_t i = 0; i < count; ++i)
    if (instances[i].deformed.present()) import_positions(cmd, instances[i].deformed, geometry_.meshes_[entries_[i]]);
  // The positions (and new slots' copies), visible to every reader of the geometry later in this frame:
  // the passes' vertex fetch and storage reads, and acceleration-structure builds (SHADER_READ).
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_COPY_BIT,
                 VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT, geometry_readers(),
                 kGeometryReads | VK_ACCESS_2_SHADER_READ_BIT);
  return entries_;
}

}  // namespace shadows::detail
