#pragma once
// The module's own small scene types: a world-space box, a caster's flags and the layout of the
// module's vertex buffer. Hosts never see them; the public API speaks of MeshDesc and Instance.
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "gpu/pipeline.hpp"
#include <shared/bounds.h>

namespace shadows::detail {

// A box; the default one is empty (invalid), which every fit and cull reads as "unbounded" or "none".
struct Aabb {
  glm::vec3 min{std::numeric_limits<float>::max()};
  glm::vec3 max{-std::numeric_limits<float>::max()};

  bool valid() const { return glm::all(glm::lessThanEqual(min, max)); }
  glm::vec3 extent() const { return max - min; }
  void extend(const glm::vec3& p) { min = glm::min(min, p), max = glm::max(max, p); }
  void extend(const Aabb& other) {
    if (other.valid()) extend(other.min), extend(other.max);
  }
  // The box around this one's eight corners moved by m (rotations make any corner an extreme).
  Aabb transformed(const glm::mat4& m) const {
    Aabb out;
    for (uint32_t i = 0; valid() && i < 8; ++i) out.extend(glm::vec3(m * glm::vec4(gpu_shared::box_corner(min, max, i), 1.0f)));
    return out;
  }
  // Wholly beyond one plane of the clip volume (shared/bounds.h); an invalid box is never outside.
  bool outside_clip(const glm::mat4& clip, const glm::vec4& ndc = glm::vec4(-1.0f, -1.0f, 1.0f, 1.0f),
                    float min_w = -std::numeric_limits<float>::max()) const {
    return valid() && gpu_shared::box_outside_clip(clip, min, max, ndc, min_w);
  }
};

// Whether a caster enters the conservative shadow map prepass (Instance::csm).
enum class CsmChoice : uint32_t { Off, On, Auto };

// What an Instance asks of its mesh as a caster.
struct CasterFlags {
  bool casts_shadow = true;
  CsmChoice csm = CsmChoice::Auto;
  bool deformed = false;  // positions of this frame's own (Instance::deformed): dynamic, never in the CSM under Auto
};

// One vertex of the module's vertex buffer (gpu::VertexInput::StandardVertex; mesh_import.comp writes it).
struct StoredVertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 uv;
};
static_assert(sizeof(StoredVertex) == engine::gpu::kStandardVertexStride);

}  // namespace shadows::detail
