#pragma once
// Dimensions of the procedural scenes, shared with the tests that check analytic answers, and the
// small mesh builders the scenes are made of.
#include <memory>
#include <string>

#include <glm/glm.hpp>

#include "engine/core/components.hpp"

namespace engine {
struct Scene;
}

namespace engine::procedural {
// `contact`: a ground plane at y = 0 with objects standing on it; light from above, slightly slanted.
namespace contact {
inline constexpr float kGroundHalfSize = 20.0f;           // ground spans [-20,20] in x and z
inline constexpr glm::vec3 kBoxCenter{0.0f, 1.0f, 0.0f};  // 2 x 2 x 2 box, top face at y = 2
inline constexpr float kBoxHalfSize = 1.0f;
inline constexpr glm::vec3 kPoleBase{-3.0f, 0.0f, 1.5f};  // thin pole: radius 0.05, height 3
inline constexpr float kPoleRadius = 0.05f;
inline constexpr float kPoleHeight = 3.0f;
inline constexpr glm::vec3 kSphereCenter{3.0f, 1.0f, 2.5f};
inline constexpr float kSphereRadius = 1.0f;
inline constexpr glm::vec3 kPlateCenter{-2.5f, 1.5f, -3.0f};  // floating plate 2 x 0.1 x 2
inline constexpr glm::vec3 kPlateHalfExtent{1.0f, 0.05f, 1.0f};
inline constexpr glm::vec3 kLightDirection{-0.35f, -1.0f, -0.25f};  // views 0 and 2 (normalised on use)
inline constexpr glm::vec3 kSphereSideLight{-1.0f, -0.35f, 0.15f};  // view 3, "sphere"
}  // namespace contact

// `atrium`: a walled courtyard with galleries along x = +-kColonnadeX and a roof at kWallHeight with
// two openings, so the floor gets a few sunlit patches and is shadowed elsewhere.
namespace atrium {
inline constexpr float kHalfSize = 8.0f;        // inner floor spans [-8,8] in x and z, top at y = 0
inline constexpr float kWallThickness = 0.4f;   // walls stand outside the floor square
inline constexpr float kWallHeight = 8.0f;      // roof slabs span y in [8, 8.3]
inline constexpr float kRoofThickness = 0.3f;
inline constexpr float kColonnadeX = 5.0f;      // columns at x = +-5, z = -6, -3, 0, 3, 6
inline constexpr float kColumnRadius = 0.3f;
inline constexpr float kColumnHeight = 4.0f;
// The two roof openings: x in [-4,4], z in [-4.5,-2] and [2,4.5].
inline constexpr float kOpeningHalfX = 4.0f;
inline constexpr float kOpeningInnerZ = 2.0f;
inline constexpr float kOpeningOuterZ = 4.5f;
inline constexpr glm::vec3 kLightDirection{-0.3f, -1.0f, -0.2f};
}  // namespace atrium

// `foliage`: a ground plane and a field of small plants made of thin branches and leaf cards.
namespace foliage {
inline constexpr float kGroundHalfSize = 15.0f;
inline constexpr int kPlantCount = 30;
inline constexpr unsigned kSeed = 0x5eed1e5u;
inline constexpr glm::vec3 kLightDirection{-0.4f, -1.0f, -0.3f};
}  // namespace foliage

// `canopy`: trees whose leaves are alpha-tested cards (a generated leaf-spray mask), over a ground.
namespace canopy {
inline constexpr float kGroundHalfSize = 15.0f;
inline constexpr int kTreeCount = 6;
inline constexpr unsigned kSeed = 0xca9091u;
inline constexpr uint32_t kLeafTextureSize = 128;
inline constexpr glm::vec3 kLightDirection{-0.3f, -1.0f, -0.25f};
}  // namespace canopy

// `lamps`: a walled corner at night under a dim moon, lit by a spot light shining down onto a box,
// through an alpha-tested grate, and a point light beside a pole and a table; a sphere stands farther
// off and a bar spins between the lights. No caster comes within 0.5 of either light.
namespace lamps {
inline constexpr glm::vec3 kSpotPosition{0.0f, 3.6f, 0.0f};
inline constexpr glm::vec3 kSpotDirection{0.15f, -1.0f, 0.1f};  // normalised on use
inline constexpr float kSpotRange = 12.0f;
inline constexpr float kSpotInnerCone = 0.5f;  // radians, half angles
inline constexpr float kSpotOuterCone = 0.72f;
inline constexpr glm::vec3 kPointPosition{3.5f, 2.2f, -3.0f};
inline constexpr float kPointRange = 8.0f;
inline constexpr glm::vec3 kMoonDirection{-0.3f, -1.0f, -0.4f};
inline constexpr glm::vec3 kNightSky{0.03f, 0.04f, 0.07f};  // Scene::sky_color
inline constexpr float kNightSkyBrightness = 0.06f;
}  // namespace lamps

// Mesh builders. All produce outward normals and counter-clockwise front faces seen from outside
// (right-handed, +Y up), so back-face culling and shadow biasing behave the same for every shape.

// Axis-aligned box: 24 vertices (flat normals), 12 triangles.
MeshData make_box(const glm::vec3& half_extent, const glm::vec3& center = glm::vec3(0.0f));
// Planar grid spanning center +- u +- v, facing normalize(cross(u, v)); 2 * subdivisions^2 triangles.
MeshData make_quad(const glm::vec3& center, const glm::vec3& u, const glm::vec3& v, int subdivisions = 1);
// Horizontal plane at height y facing +Y, spanning [-half_x, half_x] x [-half_z, half_z].
MeshData make_ground(float half_x, float half_z, float y = 0.0f, int subdivisions = 1);
// Cylinder from `base` to `top` (any direction), smooth sides, optional flat caps.
MeshData make_cylinder(const glm::vec3& base, const glm::vec3& top, float radius, int segments, bool caps = true);
MeshData make_uv_sphere(const glm::vec3& center, float radius, int slices, int stacks);
// A quad emitted twice (front and back with opposite winding and normals) so culling never drops it.
MeshData make_double_sided_quad(const glm::vec3& center, const glm::vec3& u, const glm::vec3& v);
// Appends `src` transformed by `transform` (normals by its inverse transpose) to `dst`.
void append_mesh(MeshData& dst, const MeshData& src, const glm::mat4& transform = glm::mat4(1.0f));

// A walking figure about 1.75 tall standing at `position` (feet on its y), facing +z: a root entity
// (Transform, Name = name, an AnimationPlayer playing its looping "walk" clip from `phase` seconds),
// twelve joint entities below it (hips, spine, chest, head, upper/lower legs and arms; Names
// "name/joint") and the skinned mesh entity (child of the root, identity local transform; Mesh,
// Material, ShadowCaster, Skeleton, Name = name). `tessellation` is the slices around each limb
// (32: about 14,000 triangles). Returns the root: moving it moves the figure.
Entity add_walking_figure(Scene& scene, const glm::vec3& position, float phase, uint32_t tessellation = 32,
                          const std::string& name = "character");
// The same around a mesh built before (figures may share one; each poses it with its own skeleton).
Entity add_walking_figure(Scene& scene, const glm::vec3& position, float phase,
                          const std::shared_ptr<const MeshData>& mesh, const std::string& name);
// `count` walking figures on a square grid spaced 2 units over a ground plane, each at its own phase,
// under the default sun; views: 0 overview, 1 close to the first figure's feet.
std::unique_ptr<Scene> build_character_crowd(uint32_t count);
}  // namespace engine::procedural
