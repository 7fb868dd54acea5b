#pragma once
// CPU collision for the player: the scene's static triangles in world space, binned into a uniform
// grid, queried by spheres (the player's capsule is three spheres) and by segments (tour paths).
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "engine/assets/scene.hpp"

namespace walkthrough {

class CollisionWorld {
 public:
  // Takes every mesh entity's triangles at its current world transform, except entities for which
  // `skip` returns true (moving objects).
  template <typename Skip>
  static CollisionWorld from_scene(engine::Scene& scene, Skip&& skip) {
    CollisionWorld w;
    scene.world_bounds();  // updates world transforms
    scene.registry.each<engine::Mesh, engine::Transform>([&](engine::Entity e, engine::Mesh& m, engine::Transform& t) {
      if (!m.data || skip(e)) return;
      w.add_mesh(*m.data, t.world);
    });
    w.build();
    return w;
  }
  CollisionWorld() = default;

  void add_mesh(const engine::MeshData& mesh, const glm::mat4& world);
  void build();
  size_t triangle_count() const { return triangles_.size(); }

  struct Contact {
    glm::vec3 normal{0.0f};  // from the surface towards the sphere centre
    float depth = 0.0f;      // penetration
  };
  // Pushes a sphere out of every triangle it overlaps (a few relaxation passes); returns the contacts
  // it resolved. `center` is updated.
  std::vector<Contact> resolve_sphere(glm::vec3& center, float radius) const;
  // Whether the segment a-b crosses any triangle.
  bool segment_blocked(const glm::vec3& a, const glm::vec3& b) const;
  // Distance along a downward ray from `from` to the first triangle (or -1 within max_distance).
  float ray_down(const glm::vec3& from, float max_distance) const;

 private:
  struct Triangle {
    glm::vec3 a, b, c;
  };
  using Key = int64_t;
  Key key(int x, int y, int z) const;
  glm::ivec3 cell(const glm::vec3& p) const;
  template <typename Fn>
  void for_candidates(const glm::vec3& lo, const glm::vec3& hi, Fn&& fn) const;
  bool segment_triangle(const glm::vec3& a, const glm::vec3& b, const Triangle& t, float* tout) const;

  float cell_size_ = 2.0f;
  std::vector<Triangle> triangles_;
  std::unordered_map<Key, std::vector<uint32_t>> grid_;
  mutable std::vector<uint32_t> stamp_;
  mutable uint32_t query_ = 0;
};

}  // namespace walkthrough
