#include "engine/assets/procedural_scenes.hpp"
#include "portable_random.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

#include "engine/assets/procedural_textures.hpp"
#include "engine/assets/scene.hpp"
#include "engine/core/animation.hpp"
#include "engine/core/transform_system.hpp"

namespace engine::procedural {

namespace {

constexpr float kTwoPi = glm::two_pi<float>();

uint32_t base_index(const MeshData& m) { return static_cast<uint32_t>(m.vertices.size()); }

// Any unit vector perpendicular to `n`; the pair (result, cross(n, result)) spans the plane of n.
glm::vec3 perpendicular(const glm::vec3& n) {
  const glm::vec3 helper = std::abs(n.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  return glm::normalize(glm::cross(n, helper));
}

}  // namespace

MeshData make_quad(const glm::vec3& center, const glm::vec3& u, const glm::vec3& v, int subdivisions) {
  MeshData m;
  m.name = "quad";
  const int n = std::max(1, subdivisions);
  const glm::vec3 normal = glm::normalize(glm::cross(u, v));
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const float s = float(i) / float(n);
      const float t = float(j) / float(n);
      m.vertices.push_back({center + u * (2.0f * s - 1.0f) + v * (2.0f * t - 1.0f), normal, {s, t}});
    }
  }
  const uint32_t row = uint32_t(n) + 1;
  for (uint32_t j = 0; j < uint32_t(n); ++j) {
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
      const uint32_t a = j * row + i;
      // (a, a+1, a+row+1) runs from +u towards +v: counter-clockwise around cross(u, v).
      m.indices.insert(m.indices.end(), {a, a + 1, a + row + 1, a, a + row + 1, a + row});
    }
  }
  m.compute_bounds();
  return m;
}

MeshData make_box(const glm::vec3& half_extent, const glm::vec3& center) {
  MeshData m;
  m.name = "box";
  const std::array<glm::vec3, 6> normals = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0),
                                            glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};
  for (const glm::vec3& n : normals) {
    // u, v are unit axes with cross(u, v) = n, scaled to the box's half extent on their axis.
    const glm::vec3 u_axis = perpendicular(n);
    const glm::vec3 v_axis = glm::cross(n, u_axis);
    append_mesh(m, make_quad(center + n * half_extent, u_axis * half_extent, v_axis * half_extent));
  }
  return m;
}

MeshData make_ground(float half_x, float half_z, float y, int subdivisions) {
  // cross(+x, -z) = +y.
  MeshData m = make_quad(glm::vec3(0.0f, y, 0.0f), glm::vec3(half_x, 0.0f, 0.0f), glm::vec3(0.0f, 0.0f, -half_z),
                         subdivisions);
  m.name = "ground";
  return m;
}

MeshData make_cylinder(const glm::vec3& base, const glm::vec3& top, float radius, int segments, bool caps) {
  MeshData m;
  m.name = "cylinder";
  const int segs = std::max(3, segments);
  const glm::vec3 axis = glm::normalize(top - base);
  // e1, e2, axis is right-handed, so increasing angle runs counter-clockwise seen from `top`.
  const glm::vec3 e1 = perpendicular(axis);
  const glm::vec3 e2 = glm::cross(axis, e1);
  auto ring_dir = [&](int k) {
    const float a = kTwoPi * float(k) / float(segs);
    return std::cos(a) * e1 + std::sin(a) * e2;
  };

  for (int k = 0; k <= segs; ++k) {
    const glm::vec3 d = ring_dir(k % segs);
    const float s = float(k) / float(segs);
    m.vertices.push_back({base + d * radius, d, {s, 0.0f}});
    m.vertices.push_back({top + d * radius, d, {s, 1.0f}});
  }
  for (uint32_t k = 0; k < uint32_t(segs); ++k) {
    const uint32_t b0 = 2 * k, t0 = b0 + 1, b1 = b0 + 2, t1 = b0 + 3;
    m.indices.insert(m.indices.end(), {b0, b1, t1, b0, t1, t0});
  }
  if (caps) {
    for (int side = 0; side < 2; ++side) {
      const glm::vec3 c = side == 0 ? top : base;
      const glm::vec3 n = side == 0 ? axis : -axis;
      const uint32_t center = base_index(m);
      m.vertices.push_back({c, n, {0.5f, 0.5f}});
      for (int k = 0; k < segs; ++k) {
        const glm::vec3 d = ring_dir(k);
        m.vertices.push_back({c + d * radius, n, {0.5f + 0.5f * glm::dot(d, e1), 0.5f + 0.5f * glm::dot(d, e2)}});
      }
      for (uint32_t k = 0; k < uint32_t(segs); ++k) {
        const uint32_t a = center + 1 + k;
        const uint32_t b = center + 1 + (k + 1) % uint32_t(segs);
        if (side == 0) {
          m.indices.insert(m.indices.end(), {center, a, b});
        } else {
          m.indices.insert(m.indices.end(), {center, b, a});
        }
      }
    }
  }
  m.compute_bounds();
  return m;
}

MeshData make_uv_sphere(const glm::vec3& center, float radius, int slices, int stacks) {
  MeshData m;
  m.name = "sphere";
  const int ns = std::max(3, slices);
  const int nt = std::max(2, stacks);
  for (int i = 0; i <= nt; ++i) {
    const float phi = glm::pi<float>() * float(i) / float(nt);  // 0 at the top pole
    for (int j = 0; j <= ns; ++j) {
      const float theta = kTwoPi * float(j % ns) / float(ns);
      // theta = 0 faces +z and grows towards +x: counter-clockwise seen from above.
      const glm::vec3 d{std::sin(phi) * std::sin(theta), std::cos(phi), std::sin(phi) * std::cos(theta)};
      m.vertices.push_back({center + d * radius, d, {float(j) / float(ns), float(i) / float(nt)}});
    }
  }
  const uint32_t row = uint32_t(ns) + 1;
  for (uint32_t i = 0; i < uint32_t(nt); ++i) {
    for (uint32_t j = 0; j < uint32_t(ns); ++j) {
      const uint32_t ul = i * row + j, ur = ul + 1, ll = ul + row, lr = ll + 1;
      // The pole rows collapse to a point: skip the triangle that would be degenerate there.
      if (i != 0) m.indices.insert(m.indices.end(), {ll, ur, ul});
      if (i + 1 != uint32_t(nt)) m.indices.insert(m.indices.end(), {ll, lr, ur});
    }
  }
  m.compute_bounds();
  return m;
}

MeshData make_double_sided_quad(const glm::vec3& center, const glm::vec3& u, const glm::vec3& v) {
  MeshData m = make_quad(center, u, v, 1);
  m.name = "card";
  const size_t front_vertices = m.vertices.size();
  const size_t front_indices = m.indices.size();
  for (size_t i = 0; i < front_vertices; ++i) {
    Vertex back = m.vertices[i];
    back.normal = -back.normal;
    m.vertices.push_back(back);
  }
  for (size_t t = 0; t < front_indices; t += 3) {
    const uint32_t offset = uint32_t(front_vertices);
    m.indices.insert(m.indices.end(), {m.indices[t] + offset, m.indices[t + 2] + offset, m.indices[t + 1] + offset});
  }
  return m;
}

void append_mesh(MeshData& dst, const MeshData& src, const glm::mat4& transform) {
  const uint32_t offset = base_index(dst);
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(transform)));
  for (const Vertex& v : src.vertices) {
    Vertex out = v;
    out.position = glm::vec3(transform * glm::vec4(v.position, 1.0f));
    const glm::vec3 n = normal_matrix * v.normal;
    const float len = glm::length(n);
    out.normal = len > 0.0f ? n / len : v.normal;
    dst.vertices.push_back(out);
    dst.bounds.extend(out.position);
  }
  for (uint32_t i : src.indices) dst.indices.push_back(i + offset);
}

namespace {

// Each scene owns its camera and sun as entities; views only re-aim them.
void add_camera_and_light(Scene& scene, float near_plane, float far_plane) {
  Registry& r = scene.registry;
  scene.camera = r.create();
  r.emplace<Name>(scene.camera, Name{"camera"});
  r.emplace<Transform>(scene.camera);
  Camera cam;
  cam.near_plane = near_plane;
  cam.far_plane = far_plane;
  r.emplace<Camera>(scene.camera, cam);

  scene.light = r.create();
  r.emplace<Name>(scene.light, Name{"sun"});
  r.emplace<DirectionalLight>(scene.light);
}

Entity add_mesh(Scene& scene, const std::string& name, MeshData mesh, const glm::vec4& color,
                const glm::vec3& translation = glm::vec3(0.0f)) {
  Registry& r = scene.registry;
  const Entity e = r.create();
  mesh.name = name;
  mesh.compute_bounds();
  r.emplace<Name>(e, Name{name});
  Transform t;
  t.translation = translation;
  r.emplace<Transform>(e, t);
  r.emplace<Mesh>(e, Mesh{std::make_shared<const MeshData>(std::move(mesh))});
  Material material;
  material.base_color = color;
  r.emplace<Material>(e, material);
  r.emplace<ShadowCaster>(e);
  return e;
}

void finish(Scene& scene) {
  update_world_transforms(scene.registry);
  scene.apply_view(0);
  update_world_transforms(scene.registry);
}

using Random = detail::PortableRandom;

std::unique_ptr<Scene> build_contact() {
  using namespace contact;
  auto scene = std::make_unique<Scene>();
  scene->name = "contact";
  const glm::vec4 grey{0.75f, 0.75f, 0.72f, 1.0f};
  add_mesh(*scene, "ground", make_ground(kGroundHalfSize, kGroundHalfSize, 0.0f, 4), {0.6f, 0.6f, 0.58f, 1.0f});
  add_mesh(*scene, "box", make_box(glm::vec3(kBoxHalfSize)), {0.8f, 0.35f, 0.3f, 1.0f}, kBoxCenter);
  add_mesh(*scene, "pole",
           make_cylinder(glm::vec3(0.0f), glm::vec3(0.0f, kPoleHeight, 0.0f), kPoleRadius, 16, true), grey,
           kPoleBase);
  add_mesh(*scene, "sphere", make_uv_sphere(glm::vec3(0.0f), kSphereRadius, 32, 16), {0.3f, 0.45f, 0.8f, 1.0f},
           kSphereCenter);
  add_mesh(*scene, "plate", make_box(kPlateHalfExtent), {0.35f, 0.7f, 0.35f, 1.0f}, kPlateCenter);
  add_camera_and_light(*scene, 0.05f, 200.0f);

  // View 0 sees the box top, open ground, and the ground under the plate (the eye ray to the plate's
  // shadow passes below the plate) at a square aspect.
  scene->views.push_back({"front", {0.0f, 6.0f, 12.0f}, {0.0f, 0.5f, 0.0f}, kLightDirection, glm::radians(60.0f)});
  scene->views.push_back(
      {"side", {11.0f, 4.5f, -7.0f}, {-0.5f, 0.5f, -0.5f}, {-0.8f, -0.55f, 0.35f}, glm::radians(55.0f)});
  scene->views.push_back({"top", {0.0f, 16.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, kLightDirection, glm::radians(60.0f)});
  // The sphere close up, lit from the side: its terminator crosses the view (the smooth-terminator test).
  scene->views.push_back(
      {"sphere", kSphereCenter + glm::vec3(0.4f, 0.6f, 4.2f), kSphereCenter, kSphereSideLight, glm::radians(34.0f)});
  finish(*scene);
  return scene;
}

std::unique_ptr<Scene> build_atrium() {
  using namespace atrium;
  auto scene = std::make_unique<Scene>();
  scene->name = "atrium";
  const float h = kHalfSize, outer = kHalfSize + kWallThickness;
  const glm::vec4 stone{0.78f, 0.74f, 0.66f, 1.0f};
  const glm::vec4 floor_color{0.62f, 0.6f, 0.56f, 1.0f};

  // Axis-aligned box from its min and max corners, which is how the layout below is specified.
  auto span = [](const glm::vec3& lo, const glm::vec3& hi) { return make_box((hi - lo) * 0.5f, (hi + lo) * 0.5f); };

  add_mesh(*scene, "floor", span({-outer, -0.2f, -outer}, {outer, 0.0f, outer}), floor_color);
  add_mesh(*scene, "wall_north", span({-outer, 0.0f, -outer}, {outer, kWallHeight, -h}), stone);
  add_mesh(*scene, "wall_south", span({-outer, 0.0f, h}, {outer, kWallHeight, outer}), stone);
  add_mesh(*scene, "wall_west", span({-outer, 0.0f, -h}, {-h, kWallHeight, h}), stone);
  add_mesh(*scene, "wall_east", span({h, 0.0f, -h}, {outer, kWallHeight, h}), stone);

  const float column_z[] = {-6.0f, -3.0f, 0.0f, 3.0f, 6.0f};
  const float beam_half = kColumnRadius + 0.05f;
  const float beam_bottom = kColumnHeight, beam_top = kColumnHeight + 0.6f;
  for (int side = 0; side < 2; ++side) {
    const float x = side == 0 ? -kColonnadeX : kColonnadeX;
    const char* tag = side == 0 ? "west" : "east";
    MeshData columns;
    for (float z : column_z) {
      append_mesh(columns, make_cylinder({x, 0.0f, z}, {x, kColumnHeight, z}, kColumnRadius, 12, true));
    }
    add_mesh(*scene, std::string("columns_") + tag, std::move(columns), stone);

    // Blocky arches: a lintel beam over the colonnade and stepped corbels narrowing each opening.
    MeshData arches = span({x - beam_half, beam_bottom, column_z[0] - beam_half},
                           {x + beam_half, beam_top, column_z[4] + beam_half});
    for (int i = 0; i + 1 < 5; ++i) {
      const float z0 = column_z[i], z1 = column_z[i + 1];
      append_mesh(arches, span({x - beam_half, beam_bottom - 0.4f, z0}, {x + beam_half, beam_bottom, z0 + 0.7f}));
      append_mesh(arches, span({x - beam_half, beam_bottom - 0.4f, z1 - 0.7f}, {x + beam_half, beam_bottom, z1}));
      append_mesh(arches, span({x - beam_half, beam_bottom - 0.8f, z0}, {x + beam_half, beam_bottom - 0.4f, z0 + 0.35f}));
      append_mesh(arches, span({x - beam_half, beam_bottom - 0.8f, z1 - 0.35f}, {x + beam_half, beam_bottom - 0.4f, z1}));
    }
    add_mesh(*scene, std::string("arches_") + tag, std::move(arches), stone);

    // The gallery roof shades the walkway between colonnade and wall.
    const float inner = side == 0 ? -(kColonnadeX - beam_half) : (kColonnadeX - beam_half);
    const float wall = side == 0 ? -h : h;
    add_mesh(*scene, std::string("gallery_roof_") + tag,
             span({std::min(inner, wall), beam_top, -h}, {std::max(inner, wall), beam_top + 0.3f, h}), stone);
  }

  // Roof at the wall top with two openings (x in [-4,4], z in +-[2,4.5]).
  const float y0 = kWallHeight, y1 = kWallHeight + kRoofThickness;
  const float ox = kOpeningHalfX, zi = kOpeningInnerZ, zo = kOpeningOuterZ;
  MeshData roof = span({-outer, y0, -outer}, {outer, y1, -zo});
  append_mesh(roof, span({-outer, y0, -zi}, {outer, y1, zi}));
  append_mesh(roof, span({-outer, y0, zo}, {outer, y1, outer}));
  for (float sz : {-1.0f, 1.0f}) {
    const float za = std::min(sz * zi, sz * zo), zb = std::max(sz * zi, sz * zo);
    append_mesh(roof, span({-outer, y0, za}, {-ox, y1, zb}));
    append_mesh(roof, span({ox, y0, za}, {outer, y1, zb}));
  }
  add_mesh(*scene, "roof", std::move(roof), stone);

  add_camera_and_light(*scene, 0.05f, 150.0f);
  scene->views.push_back({"inside", {3.0f, 1.7f, 7.0f}, {-1.5f, 0.6f, -2.0f}, kLightDirection, glm::radians(70.0f)});
  // Sees the whole roof; the line of sight to the target passes through the southern opening.
  scene->views.push_back({"above", {2.0f, 24.0f, 6.0f}, {0.0f, 0.0f, 0.5f}, kLightDirection, glm::radians(60.0f)});
  scene->views.push_back(
      {"gallery", {6.6f, 1.7f, -7.4f}, {6.4f, 1.4f, 7.0f}, kLightDirection, glm::radians(60.0f)});
  finish(*scene);
  return scene;
}

std::unique_ptr<Scene> build_foliage() {
  using namespace foliage;
  auto scene = std::make_unique<Scene>();
  scene->name = "foliage";
  Random rng(kSeed);
  add_mesh(*scene, "ground", make_ground(kGroundHalfSize, kGroundHalfSize, 0.0f, 8), {0.42f, 0.38f, 0.3f, 1.0f});

  // Plants on a jittered 6 x 5 grid over x in [-10,10], z in [-8,8].
  constexpr int kColumns = 6;
  for (int p = 0; p < kPlantCount; ++p) {
    const int gx = p % kColumns, gz = p / kColumns;
    const glm::vec3 origin{-10.0f + 20.0f * (float(gx) + 0.5f) / float(kColumns) + rng.uniform(-1.0f, 1.0f), 0.0f,
                           -8.0f + 16.0f * (float(gz) + 0.5f) / 5.0f + rng.uniform(-1.0f, 1.0f)};
    const float height = rng.uniform(1.0f, 2.5f);
    const float trunk_top = height * 0.65f;

    MeshData branches = make_cylinder({0, 0, 0}, {0, trunk_top, 0}, rng.uniform(0.035f, 0.07f), 6, true);
    MeshData leaves;
    const int branch_count = rng.integer(5, 8);
    for (int b = 0; b <= branch_count; ++b) {
      // The last "branch" continues the trunk upwards; the others leave it sideways and up.
      glm::vec3 start, end;
      if (b == branch_count) {
        start = {0.0f, trunk_top, 0.0f};
        end = {rng.uniform(-0.1f, 0.1f), height, rng.uniform(-0.1f, 0.1f)};
      } else {
        const float angle = kTwoPi * (float(b) + rng.uniform(0.0f, 0.6f)) / float(branch_count);
        start = {0.0f, trunk_top * rng.uniform(0.45f, 1.0f), 0.0f};
        const float length = rng.uniform(0.4f, 0.9f);
        const glm::vec3 dir = glm::normalize(glm::vec3(std::cos(angle), rng.uniform(0.4f, 1.0f), std::sin(angle)));
        end = start + dir * length;
      }
      append_mesh(branches, make_cylinder(start, end, rng.uniform(0.012f, 0.022f), 5, false));

      const int leaf_count = rng.integer(28, 40);
      for (int l = 0; l < leaf_count; ++l) {
        // Leaves cluster around the outer part of the branch.
        const glm::vec3 on_branch = glm::mix(start, end, rng.uniform(0.35f, 1.0f));
        const glm::vec3 center = on_branch + rng.unit_vector() * rng.uniform(0.02f, 0.25f);
        const glm::vec3 n = rng.unit_vector();
        const glm::vec3 a = perpendicular(n);
        const glm::vec3 bvec = glm::cross(n, a);
        const float spin = rng.uniform(0.0f, kTwoPi);
        const glm::vec3 u_dir = std::cos(spin) * a + std::sin(spin) * bvec;
        const glm::vec3 v_dir = glm::cross(n, u_dir);
        const float half_len = rng.uniform(0.05f, 0.15f);
        const float half_width = half_len * rng.uniform(0.4f, 0.8f);
        append_mesh(leaves, make_double_sided_quad(center, u_dir * half_len, v_dir * half_width));
      }
    }
    char suffix[8];
    std::snprintf(suffix, sizeof(suffix), "%02d", p);
    add_mesh(*scene, std::string("branches_") + suffix, std::move(branches), {0.4f, 0.28f, 0.17f, 1.0f}, origin);
    const glm::vec4 green{0.22f + rng.uniform(0.0f, 0.1f), 0.45f + rng.uniform(0.0f, 0.15f), 0.14f, 1.0f};
    add_mesh(*scene, std::string("leaves_") + suffix, std::move(leaves), green, origin);
  }

  add_camera_and_light(*scene, 0.03f, 120.0f);
  scene->views.push_back(
      {"overview", {0.0f, 7.0f, 16.0f}, {0.0f, 0.8f, 0.0f}, kLightDirection, glm::radians(60.0f)});
  scene->views.push_back(
      {"understory", {2.0f, 1.0f, 5.0f}, {-2.0f, 0.7f, -4.0f}, {-0.7f, -0.6f, -0.4f}, glm::radians(65.0f)});
  finish(*scene);
  return scene;
}

// Trees whose leaves are cut-out cards: each card a double-sided quad showing a generated spray of
// leaves (alpha-tested, MASK at 0.5), so shadows on the ground and trunks are leaf-shaped with light
// between the leaves.
std::unique_ptr<Scene> build_canopy() {
  using namespace canopy;
  auto scene = std::make_unique<Scene>();
  scene->name = "canopy";
  Random rng(kSeed);
  add_mesh(*scene, "ground", make_ground(kGroundHalfSize, kGroundHalfSize, 0.0f, 8), {0.5f, 0.46f, 0.36f, 1.0f});
  const auto spray = make_leaf_spray_texture(kLeafTextureSize, 7);
  for (int p = 0; p < kTreeCount; ++p) {
    const float angle = kTwoPi * float(p) / float(kTreeCount) + rng.uniform(-0.3f, 0.3f);
    const float radius = p == 0 ? 0.0f : rng.uniform(3.0f, 6.0f);
    const glm::vec3 origin{radius * std::cos(angle), 0.0f, radius * std::sin(angle)};
    const float height = rng.uniform(2.6f, 3.6f);
    MeshData wood = make_cylinder({0, 0, 0}, {0, height, 0}, rng.uniform(0.08f, 0.12f), 10, true);
    MeshData cards;
    const int branch_count = rng.integer(5, 7);
    for (int b = 0; b < branch_count; ++b) {
      const float a = kTwoPi * (float(b) + rng.uniform(0.0f, 0.5f)) / float(branch_count);
      const glm::vec3 start{0.0f, height * rng.uniform(0.55f, 0.95f), 0.0f};
      const glm::vec3 dir = glm::normalize(glm::vec3(std::cos(a), rng.uniform(0.2f, 0.7f), std::sin(a)));
      const glm::vec3 end = start + dir * rng.uniform(0.9f, 1.5f);
      append_mesh(wood, make_cylinder(start, end, 0.035f, 6, false));
      const int card_count = rng.integer(4, 6);
      for (int c = 0; c < card_count; ++c) {
        // A card hangs from a point on the outer branch, its leaves fanning outward and roughly up.
        const glm::vec3 attach = glm::mix(start, end, rng.uniform(0.4f, 1.0f));
        const glm::vec3 out = glm::normalize(dir + glm::vec3(0.0f, rng.uniform(0.2f, 0.8f), 0.0f) + rng.unit_vector() * 0.5f);
        const glm::vec3 side = glm::normalize(glm::cross(out, perpendicular(out)) + rng.unit_vector() * 0.3f);
        const glm::vec3 across = glm::normalize(glm::cross(out, side));
        const float half = rng.uniform(0.35f, 0.55f);
        // make_quad's t = 1 edge (the texture's bottom row, where the stems meet) sits at the branch.
        append_mesh(cards, make_double_sided_quad(attach + out * half, across * half, -out * half));
      }
    }
    char suffix[8];
    std::snprintf(suffix, sizeof(suffix), "%02d", p);
    add_mesh(*scene, std::string("wood_") + suffix, std::move(wood), {0.42f, 0.3f, 0.2f, 1.0f}, origin);
    const Entity leaves = add_mesh(*scene, std::string("leaf_cards_") + suffix, std::move(cards), glm::vec4(1.0f), origin);
    Material& material = scene->registry.get<Material>(leaves);
    material.alpha_mode = AlphaMode::Mask;
    material.alpha_cutoff = 0.5f;
    material.base_color_texture = spray;
  }
  add_camera_and_light(*scene, 0.03f, 120.0f);
  scene->views.push_back({"overview", {0.0f, 6.0f, 13.0f}, {0.0f, 1.2f, 0.0f}, kLightDirection, glm::radians(60.0f)});
  scene->views.push_back({"ground", {1.5f, 4.5f, 4.5f}, {-0.5f, 0.0f, -1.0f}, {0.45f, -1.0f, 0.2f}, glm::radians(65.0f)});
  finish(*scene);
  return scene;
}

std::unique_ptr<Scene> build_lamps() {
  using namespace lamps;
  auto scene = std::make_unique<Scene>();
  scene->name = "lamps";
  const glm::vec4 plaster{0.78f, 0.76f, 0.72f, 1.0f};
  add_mesh(*scene, "floor", make_ground(8.0f, 8.0f, 0.0f, 4), {0.55f, 0.5f, 0.45f, 1.0f});
  add_mesh(*scene, "wall_back", make_box({6.0f, 2.0f, 0.15f}), plaster, {0.0f, 2.0f, -6.15f});
  add_mesh(*scene, "wall_left", make_box({0.15f, 2.0f, 6.0f}), plaster, {-6.15f, 2.0f, 0.0f});
  add_mesh(*scene, "box", make_box(glm::vec3(0.5f)), {0.8f, 0.35f, 0.3f, 1.0f}, {0.6f, 0.5f, 0.5f});
  add_mesh(*scene, "pole", make_cylinder(glm::vec3(0.0f), {0.0f, 1.8f, 0.0f}, 0.08f, 16, true), plaster,
           {2.9f, 0.0f, -2.3f});
  add_mesh(*scene, "table", make_box({0.8f, 0.05f, 0.5f}), {0.45f, 0.3f, 0.2f, 1.0f}, {2.6f, 1.0f, -0.8f});
  add_mesh(*scene, "sphere", make_uv_sphere(glm::vec3(0.0f), 0.8f, 32, 16), {0.3f, 0.45f, 0.8f, 1.0f},
           {-2.6f, 0.8f, 2.2f});
  // The grate, 1.2 under the spot light: its bars cast a lattice onto the box and the floor.
  const Entity grate = add_mesh(*scene, "grate",
                                make_double_sided_quad(glm::vec3(0.0f), {0.7f, 0.0f, 0.0f}, {0.0f, 0.0f, -0.7f}),
                                glm::vec4(1.0f), {-0.2f, 2.4f, 0.0f});
  Material& metal = scene->registry.get<Material>(grate);
  metal.alpha_mode = AlphaMode::Mask;
  metal.alpha_cutoff = 0.5f;
  metal.base_color_texture = make_grate_texture(64, 6, 0.3f);
  // The moving caster: a bar spinning about the vertical between the lights.
  const Entity bar = add_mesh(*scene, "spinning_bar", make_box({0.6f, 0.06f, 0.06f}), {0.7f, 0.7f, 0.2f, 1.0f},
                              {1.6f, 1.7f, -1.6f});
  Animated spin;
  spin.kind = Animated::Kind::Spin;
  spin.speed = 1.2f;
  scene->registry.emplace<Animated>(bar, spin);

  Registry& r = scene->registry;
  const Entity spot = r.create();
  r.emplace<Name>(spot, Name{"spot_light"});
  Transform spot_transform;
  spot_transform.translation = kSpotPosition;
  spot_transform.rotation = glm::rotation(glm::vec3(0.0f, 0.0f, -1.0f), glm::normalize(kSpotDirection));
  r.emplace<Transform>(spot, spot_transform);
  r.emplace<SpotLight>(spot, SpotLight{{1.0f, 0.85f, 0.6f}, 60.0f, kSpotRange, kSpotInnerCone, kSpotOuterCone});
  const Entity point = r.create();
  r.emplace<Name>(point, Name{"point_light"});
  Transform point_transform;
  point_transform.translation = kPointPosition;
  r.emplace<Transform>(point, point_transform);
  r.emplace<PointLight>(point, PointLight{{0.7f, 0.8f, 1.0f}, 25.0f, kPointRange});

  add_camera_and_light(*scene, 0.03f, 100.0f);
  DirectionalLight& moon = r.get<DirectionalLight>(scene->light);
  moon.direction = glm::normalize(kMoonDirection);
  moon.color = {0.6f, 0.7f, 1.0f};
  moon.intensity = 0.15f;
  scene->sky_color = kNightSky;
  scene->sky_brightness = kNightSkyBrightness;
  scene->views.push_back({"overview", {6.0f, 6.5f, 7.0f}, {0.0f, 0.5f, -1.0f}, kMoonDirection, glm::radians(60.0f)});
  scene->views.push_back({"by_the_lamps", {4.8f, 1.7f, 3.2f}, {0.6f, 0.7f, -1.2f}, kMoonDirection, glm::radians(65.0f)});
  finish(*scene);
  return scene;
}

// A hall about 60 units across and 30 high, the scale of a game level's room: pillars, crates and a
// gallery, lit by three spot lights 20 to 50 units from what they light and a point light under the
// gallery, with a dim moon through the open roof. Shadows here travel tens of units, where a
// light-space depth or ray offset made for a metre-sized scene loses its precision.
std::unique_ptr<Scene> build_hall() {
  auto scene = std::make_unique<Scene>();
  scene->name = "hall";
  const glm::vec4 stone{0.7f, 0.68f, 0.64f, 1.0f};
  add_mesh(*scene, "floor", make_ground(30.0f, 30.0f, 0.0f, 8), {0.5f, 0.47f, 0.43f, 1.0f});
  add_mesh(*scene, "wall_north", make_box({30.0f, 15.0f, 0.5f}), stone, {0.0f, 15.0f, -30.5f});
  add_mesh(*scene, "wall_west", make_box({0.5f, 15.0f, 30.0f}), stone, {-30.5f, 15.0f, 0.0f});
  add_mesh(*scene, "wall_east", make_box({0.5f, 15.0f, 30.0f}), stone, {30.5f, 15.0f, 0.0f});
  for (int i = 0; i < 6; ++i) {
    const glm::vec3 base{-20.0f + 8.0f * float(i), 0.0f, -12.0f};
    char name[16];
    std::snprintf(name, sizeof(name), "pillar_%d", i);
    add_mesh(*scene, name, make_cylinder(glm::vec3(0.0f), {0.0f, 18.0f, 0.0f}, 1.1f, 24, true), stone, base);
  }
  // The gallery on the pillars, and crates on the floor.
  add_mesh(*scene, "gallery", make_box({22.0f, 0.6f, 4.0f}), {0.45f, 0.32f, 0.22f, 1.0f}, {0.0f, 18.6f, -16.0f});
  const glm::vec3 crates[5][2] = {{{-12.0f, 1.5f, 6.0f}, glm::vec3(1.5f)},
                                  {{-9.2f, 1.0f, 7.5f}, glm::vec3(1.0f)},
                                  {{4.0f, 2.5f, 2.0f}, {2.5f, 2.5f, 2.5f}},
                                  {{14.0f, 1.2f, 10.0f}, {3.0f, 1.2f, 1.2f}},
                                  {{8.0f, 0.6f, -4.0f}, {0.6f, 0.6f, 0.6f}}};
  for (int i = 0; i < 5; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "crate_%d", i);
    add_mesh(*scene, name, make_box(crates[i][1]), {0.6f, 0.42f, 0.25f, 1.0f}, crates[i][0]);
  }
  add_mesh(*scene, "statue", make_uv_sphere(glm::vec3(0.0f), 2.0f, 32, 16), {0.75f, 0.75f, 0.8f, 1.0f}, {-4.0f, 2.0f, 14.0f});

  Registry& r = scene->registry;
  // Three spot lights high on the walls and under the roof, aimed at the floor 20 to 50 units away.
  const struct {
    const char* name;
    glm::vec3 position, target, color;
    float range, outer;
  } spots[3] = {{"spot_west", {-29.0f, 26.0f, 10.0f}, {-6.0f, 0.0f, 8.0f}, {1.0f, 0.85f, 0.6f}, 70.0f, 0.5f},
                {"spot_east", {29.0f, 22.0f, -4.0f}, {10.0f, 0.0f, 6.0f}, {0.7f, 0.85f, 1.0f}, 60.0f, 0.55f},
                {"spot_roof", {2.0f, 29.0f, 4.0f}, {2.0f, 0.0f, 4.0f}, {1.0f, 1.0f, 0.9f}, 45.0f, 0.6f}};
  for (const auto& s : spots) {
    const Entity e = r.create();
    r.emplace<Name>(e, Name{s.name});
    Transform t;
    t.translation = s.position;
    t.rotation = glm::rotation(glm::vec3(0.0f, 0.0f, -1.0f), glm::normalize(s.target - s.position));
    r.emplace<Transform>(e, t);
    r.emplace<SpotLight>(e, SpotLight{s.color, 900.0f, s.range, 0.6f * s.outer, s.outer});
  }
  const Entity point = r.create();
  r.emplace<Name>(point, Name{"lamp_under_gallery"});
  Transform point_transform;
  point_transform.translation = {-6.0f, 12.0f, -10.0f};
  r.emplace<Transform>(point, point_transform);
  r.emplace<PointLight>(point, PointLight{{1.0f, 0.8f, 0.55f}, 150.0f, 35.0f});

  add_camera_and_light(*scene, 0.1f, 300.0f);
  const glm::vec3 moon_direction{0.35f, -1.0f, 0.25f};
  DirectionalLight& moon = r.get<DirectionalLight>(scene->light);
  moon.direction = glm::normalize(moon_direction);
  moon.color = {0.6f, 0.7f, 1.0f};
  moon.intensity = 0.3f;
  scene->sky_color = {0.05f, 0.06f, 0.1f};
  scene->sky_brightness = 0.15f;
  scene->views.push_back({"overview", {26.0f, 24.0f, 28.0f}, {-2.0f, 2.0f, 0.0f}, moon_direction, glm::radians(60.0f)});
  scene->views.push_back({"floor", {16.0f, 2.0f, 22.0f}, {-6.0f, 3.0f, -6.0f}, moon_direction, glm::radians(65.0f)});
  finish(*scene);
  return scene;
}

}  // namespace

}  // namespace engine::procedural

namespace engine {

std::vector<std::string> procedural_scene_names() {
  return {"contact", "atrium", "foliage", "canopy", "lamps", "hall", "characters"};
}

std::unique_ptr<Scene> build_procedural_scene(const std::string& name) {
  if (name == "contact") return procedural::build_contact();
  if (name == "atrium") return procedural::build_atrium();
  if (name == "foliage") return procedural::build_foliage();
  if (name == "canopy") return procedural::build_canopy();
  if (name == "lamps") return procedural::build_lamps();
  if (name == "hall") return procedural::build_hall();
  if (name == "characters") return procedural::build_character_crowd(100);
  throw SceneError("unknown procedural scene '" + name +
                   "': expected one of contact, atrium, foliage, canopy, lamps, hall, characters");
}

}  // namespace engine
