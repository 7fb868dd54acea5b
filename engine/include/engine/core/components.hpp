#pragma once
// The components every part of the engine and its modules agree on.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "engine/core/ecs.hpp"

namespace engine {

struct Name {
  std::string value;
};

// Local transform relative to `parent` (or the world when parent is null). `world` is derived each
// frame by the transform system; read it, do not write it.
struct Transform {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 scale{1.0f};
  Entity parent = kNullEntity;
  glm::mat4 world{1.0f};

  glm::mat4 local_matrix() const;
};

// A world matrix (Transform::world) moved by `shift`, added to its translation in double: how a frame
// rebases the scene to its local origin (engine::FrameView; shift = Scene::origin - FrameView::origin).
// The renderer and the reference both take their matrices from here, so they draw and trace the same
// float triangles.
glm::mat4 rebased(const glm::mat4& world, const glm::dvec3& shift);

struct Aabb {
  glm::vec3 min{std::numeric_limits<float>::max()};
  glm::vec3 max{-std::numeric_limits<float>::max()};
  void extend(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void extend(const Aabb& b) {
    if (b.valid()) {
      extend(b.min);
      extend(b.max);
    }
  }
  bool valid() const { return min.x <= max.x && min.y <= max.y && min.z <= max.z; }
  glm::vec3 center() const { return (min + max) * 0.5f; }
  glm::vec3 extent() const { return max - min; }
  Aabb transformed(const glm::mat4& m) const;
  // True when the box lies wholly on the far side of one plane of the clip-space volume
  // x/w in [ndc.x, ndc.z], y/w in [ndc.y, ndc.w], w >= min_w: nothing of it can reach that view.
  // Each test is a half-space in world space, so it holds for corners behind a perspective camera too.
  bool outside_clip(const glm::mat4& clip, const glm::vec4& ndc = glm::vec4(-1.0f, -1.0f, 1.0f, 1.0f),
                    float min_w = -std::numeric_limits<float>::max()) const;
};

struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec2 uv;
};
// The layout gpu::VertexInput::StandardVertex reads.
static_assert(sizeof(Vertex) == 32 && offsetof(Vertex, normal) == 12 && offsetof(Vertex, uv) == 24);

struct DeformData;  // engine/core/skinning.hpp

// CPU copy of a triangle mesh, kept after upload: the reference tracer, the automatic CSM choice and
// the tests read it.
struct MeshData {
  std::string name;
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;  // triangle list
  Aabb bounds;  // of the rest positions
  // Skin and morph targets (engine/core/skinning.hpp); null for a rigid mesh.
  std::shared_ptr<const DeformData> deform;
  void compute_bounds();
  size_t triangle_count() const { return indices.size() / 3; }
};

struct Mesh {
  std::shared_ptr<const MeshData> data;
  uint32_t gpu_mesh = UINT32_MAX;  // slot in the renderer's geometry buffers, assigned at upload
};

enum class AlphaMode : uint32_t { Opaque = 0, Mask = 1, Blend = 2 };

// How texture coordinates outside [0,1] fold back (glTF sampler wrapS / wrapT).
enum class TextureWrap : uint32_t { Repeat = 0, ClampToEdge = 1, MirroredRepeat = 2 };

// A decoded RGBA8 image (sRGB colour, linear alpha), rows top to bottom. Every technique and the
// reference read it with one rule, the nearest texel of this level (shared/material.h), so alpha
// tests agree exactly.
struct Texture {
  std::string name;  // file or generator, for messages
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> rgba;
  TextureWrap wrap_s = TextureWrap::Repeat;
  TextureWrap wrap_t = TextureWrap::Repeat;
};

struct Material {
  glm::vec4 base_color{0.8f, 0.8f, 0.8f, 1.0f};
  AlphaMode alpha_mode = AlphaMode::Opaque;
  float alpha_cutoff = 0.5f;
  std::shared_ptr<const Texture> base_color_texture;  // multiplies base_color; null: the factor alone
};

// Whether the material cuts holes by alpha: MASK, and BLEND, which a deferred renderer cannot blend
// and so tests against 0.5 (its cut-outs stay; its translucency is lost).
bool alpha_tested(const Material& m);
// The least texel alpha byte (0..255) that keeps a texel of an alpha-tested material:
// base_color.a * byte / 255 >= cutoff. 256: nothing is kept; 0: everything. Computed once here so
// every shader and the reference compare integers and agree exactly.
uint32_t alpha_threshold(const Material& m);
// The same rule for a texture alpha scaled by `scale` (the base colour's alpha) against `cutoff`.
uint32_t alpha_threshold(float cutoff, float scale);

struct Camera {
  float vertical_fov = glm::radians(60.0f);
  float near_plane = 0.05f;
  float far_plane = 200.0f;
  // Derived each frame from the entity's world transform and the output aspect ratio.
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};
};

// A sun: light travels along `direction` (pointing from the light into the scene).
struct DirectionalLight {
  glm::vec3 direction{-0.4f, -1.0f, -0.3f};
  glm::vec3 color{1.0f, 0.97f, 0.9f};
  float intensity = 3.0f;
  // The sun's angular diameter in degrees (0.53: the real sun; 0: a point, hard shadows; at most 10).
  // Soft-shadow techniques widen their penumbrae with it (shadows::Light::angular_diameter_degrees).
  float angular_diameter_degrees = 0.53f;
};

// A spot light at the entity's world position, shining down its local -Z axis (glTF's
// KHR_lights_punctual convention). Intensity in candela as glTF; range in world units (> 0: shadows
// need a finite reach); cone half-angles in radians, 0 <= inner_cone < outer_cone <= pi/2.
struct SpotLight {
  glm::vec3 color{1.0f};
  float intensity = 10.0f;
  float range = 10.0f;
  float inner_cone = 0.0f;
  float outer_cone = 0.7853982f;
  bool enabled = true;  // off: the renderer neither lights nor shadows with it
  float radius = 0.0f;  // the emitting sphere's radius in world units (0: a point, hard shadows)
};

// A point light at the entity's world position; units as SpotLight.
struct PointLight {
  glm::vec3 color{1.0f};
  float intensity = 10.0f;
  float range = 10.0f;
  bool enabled = true;  // off: the renderer neither lights nor shadows with it
  float radius = 0.0f;  // the emitting sphere's radius in world units (0: a point, hard shadows)
};

// Whether this mesh enters the conservative shadow map z-prepass.
enum class CsmChoice : uint32_t { Off = 0, On = 1, Auto = 2 };

struct ShadowCaster {
  bool casts_shadow = true;
  bool receives_shadow = true;
  CsmChoice csm = CsmChoice::Auto;
};

// Whether a game's player collides with this mesh (scene files: "collide"; plants default to false).
struct Collider {
  bool solid = true;
};

}  // namespace engine
