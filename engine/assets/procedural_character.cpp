// A procedural walking figure: one skinned mesh of capsules and spheres on a 12-joint skeleton, with a
// looping walk clip, and a crowd of them for deformation at scale.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

#include "engine/assets/procedural_scenes.hpp"
#include "engine/assets/scene.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"

namespace engine::procedural {

namespace {

enum Joint : uint32_t {
  kHips, kSpine, kChest, kHead, kLeftUpperLeg, kLeftLowerLeg, kRightUpperLeg, kRightLowerLeg,
  kLeftUpperArm, kLeftLowerArm, kRightUpperArm, kRightLowerArm, kJointCount
};

struct JointRest {
  const char* name;
  int parent;  // -1: the figure's root
  glm::vec3 offset;  // rest translation relative to the parent; rest rotations are identity
};

// The figure faces +z with +x on its left; 1.75 tall with its feet on y = 0.
constexpr std::array<JointRest, kJointCount> kRest = {{
    {"hips", -1, {0.0f, 0.95f, 0.0f}},
    {"spine", kHips, {0.0f, 0.12f, 0.0f}},
    {"chest", kSpine, {0.0f, 0.25f, 0.0f}},
    {"head", kChest, {0.0f, 0.20f, 0.0f}},
    {"left_upper_leg", kHips, {0.1f, -0.05f, 0.0f}},
    {"left_lower_leg", kLeftUpperLeg, {0.0f, -0.42f, 0.0f}},
    {"right_upper_leg", kHips, {-0.1f, -0.05f, 0.0f}},
    {"right_lower_leg", kRightUpperLeg, {0.0f, -0.42f, 0.0f}},
    {"left_upper_arm", kChest, {0.24f, 0.12f, 0.0f}},
    {"left_lower_arm", kLeftUpperArm, {0.0f, -0.28f, 0.0f}},
    {"right_upper_arm", kChest, {-0.24f, 0.12f, 0.0f}},
    {"right_lower_arm", kRightUpperArm, {0.0f, -0.28f, 0.0f}},
}};

constexpr float kWalkPeriod = 1.1f;  // seconds per stride (two steps)
constexpr float kBlend = 0.07f;      // half-width of the skin blend across a joint

// A joint's rest position relative to the figure's root.
glm::vec3 rest_position(uint32_t j) {
  glm::vec3 p(0.0f);
  for (int k = int(j); k >= 0; k = kRest[size_t(k)].parent) p += kRest[size_t(k)].offset;
  return p;
}

// A capsule along +y from y = 0 to y = length with hemispherical ends: `rings` rows along the body so
// it bends smoothly when its ends follow different joints.
MeshData make_capsule(float length, float radius, int slices, int cap_stacks, int rings) {
  MeshData m;
  std::vector<std::pair<float, float>> rows;  // (phi from the top pole, y of the row's centre)
  for (int i = 0; i <= cap_stacks; ++i) rows.push_back({glm::half_pi<float>() * float(i) / float(cap_stacks), length});
  for (int k = 1; k < rings; ++k) rows.push_back({glm::half_pi<float>(), length * (1.0f - float(k) / float(rings))});
  for (int i = 0; i <= cap_stacks; ++i)
    rows.push_back({glm::half_pi<float>() * (1.0f + float(i) / float(cap_stacks)), 0.0f});
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto [phi, y] = rows[i];
    for (int j = 0; j <= slices; ++j) {
      const float theta = glm::two_pi<float>() * float(j % slices) / float(slices);
      const glm::vec3 d{std::sin(phi) * std::sin(theta), std::cos(phi), std::sin(phi) * std::cos(theta)};
      m.vertices.push_back({glm::vec3(0.0f, y, 0.0f) + d * radius, d, {float(j) / float(slices), float(i) / float(rows.size() - 1)}});
    }
  }
  const uint32_t row = uint32_t(slices) + 1;
  const uint32_t last = uint32_t(rows.size()) - 1;
  for (uint32_t i = 0; i < last; ++i) {
    for (uint32_t j = 0; j < uint32_t(slices); ++j) {
      const uint32_t ul = i * row + j, ur = ul + 1, ll = ul + row, lr = ll + 1;
      // The pole rows collapse to a point: skip the triangle that would be degenerate there.
      if (i != 0) m.indices.insert(m.indices.end(), {ll, ur, ul});
      if (i + 1 != last) m.indices.insert(m.indices.end(), {ll, lr, ur});
    }
  }
  return m;
}

// Skin weights along a chain of joints laid out along `axis` from `origin`: joint k owns the stretch
// past its start coordinate, blended smoothly with its neighbour across +-kBlend, so at most two
// joints move a vertex and the weights sum to 1.
struct Chain {
  glm::vec3 origin;
  glm::vec3 axis;
  std::vector<std::pair<uint32_t, float>> joints;  // (joint, start coordinate); the first has none
};

void skin_part(const Chain& chain, const std::vector<Vertex>& vertices, size_t first, DeformData& d) {
  for (size_t v = first; v < vertices.size(); ++v) {
    const float t = glm::dot(vertices[v].position - chain.origin, chain.axis);
    glm::uvec4 joints(0u);
    glm::vec4 weights(0.0f);
    int used = 0;
    for (size_t k = 0; k < chain.joints.size(); ++k) {
      const float begin = k == 0 ? 1.0f : glm::smoothstep(chain.joints[k].second - kBlend, chain.joints[k].second + kBlend, t);
      const float end = k + 1 == chain.joints.size()
                            ? 0.0f
                            : glm::smoothstep(chain.joints[k + 1].second - kBlend, chain.joints[k + 1].second + kBlend, t);
      const float w = begin - end;
      if (w > 0.0f && used < 4) joints[used] = chain.joints[k].first, weights[used] = w, ++used;
    }
    d.joints.push_back(joints);
    d.weights.push_back(weights / (weights.x + weights.y + weights.z + weights.w));
  }
}

// Appends one body part (`part` placed by `place`) skinned along `chain`.
void add_part(MeshData& mesh, DeformData& d, const MeshData& part, const glm::mat4& place, const Chain& chain) {
  const size_t first = mesh.vertices.size();
  append_mesh(mesh, part, place);
  skin_part(chain, mesh.vertices, first, d);
}

// Places a +y capsule so that it runs from `a` to `b`.
glm::mat4 along(const glm::vec3& a, const glm::vec3& b) {
  return glm::translate(glm::mat4(1.0f), a) * glm::toMat4(glm::rotation(glm::vec3(0.0f, 1.0f, 0.0f), glm::normalize(b - a)));
}

void add_limb(MeshData& mesh, DeformData& d, int slices, int stacks, int rings, uint32_t parent, uint32_t upper,
              uint32_t lower, const glm::vec3& end, float r_upper, float r_lower) {
  const glm::vec3 top = rest_position(upper), mid = rest_position(lower);
  const glm::vec3 axis(0.0f, -1.0f, 0.0f);
  const Chain chain{glm::vec3(0.0f), axis, {{parent, 0.0f}, {upper, -top.y}, {lower, -mid.y}}};
  add_part(mesh, d, make_capsule(top.y - mid.y, r_upper, slices, stacks, rings), along(mid, top), chain);
  add_part(mesh, d, make_capsule(mid.y - end.y, r_lower, slices, stacks, rings), along(end, mid), chain);
}

MeshData build_figure_mesh(uint32_t tessellation) {
  const int slices = std::max(6, int(tessellation));
  const int stacks = std::max(2, slices / 8), rings = std::max(2, slices / 4);
  MeshData mesh;
  mesh.name = "character";
  auto d = std::make_shared<DeformData>();
  d->joint_count = kJointCount;
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  const Chain trunk{glm::vec3(0.0f), up, {{kHips, 0.0f}, {kSpine, rest_position(kSpine).y}, {kChest, rest_position(kChest).y}}};
  // Torso: a capsule flattened front to back, from the pelvis to the shoulders.
  const glm::mat4 flatten = glm::scale(glm::mat4(1.0f), {1.0f, 1.0f, 0.65f});
  add_part(mesh, *d, make_capsule(0.41f, 0.16f, slices, stacks, rings),
           glm::translate(glm::mat4(1.0f), {0.0f, 0.95f, 0.0f}) * flatten, trunk);
  add_part(mesh, *d, make_uv_sphere(glm::vec3(0.0f), 1.0f, slices, slices / 2),
           glm::translate(glm::mat4(1.0f), {0.0f, 0.92f, 0.0f}) * glm::scale(glm::mat4(1.0f), {0.17f, 0.12f, 0.12f}), trunk);
  const Chain neck{glm::vec3(0.0f), up, {{kChest, 0.0f}, {kHead, rest_position(kHead).y}}};
  add_part(mesh, *d, make_capsule(0.14f, 0.05f, slices, stacks, rings), glm::translate(glm::mat4(1.0f), {0.0f, 1.44f, 0.0f}), neck);
  add_part(mesh, *d, make_uv_sphere({0.0f, 1.64f, 0.0f}, 0.11f, slices, slices / 2), glm::mat4(1.0f), neck);
  for (const float side : {1.0f, -1.0f}) {
    const bool left = side > 0.0f;
    const uint32_t upper_leg = left ? kLeftUpperLeg : kRightUpperLeg, lower_leg = left ? kLeftLowerLeg : kRightLowerLeg;
    const uint32_t upper_arm = left ? kLeftUpperArm : kRightUpperArm, lower_arm = left ? kLeftLowerArm : kRightLowerArm;
    const float x = rest_position(upper_leg).x;
    add_limb(mesh, *d, slices, stacks, rings, kHips, upper_leg, lower_leg, {x, 0.1f, 0.0f}, 0.075f, 0.055f);
    // The foot follows the shin: a stiff ankle keeps the weights simple.
    const Chain foot{glm::vec3(0.0f), up, {{lower_leg, 0.0f}}};
    add_part(mesh, *d, make_capsule(0.2f, 0.045f, slices, stacks, rings), along({x, 0.045f, -0.05f}, {x, 0.045f, 0.15f}), foot);
    const float ax = rest_position(upper_arm).x;
    add_limb(mesh, *d, slices, stacks, rings, kChest, upper_arm, lower_arm, {ax, 0.9f, 0.0f}, 0.045f, 0.04f);
    const Chain hand{glm::vec3(0.0f), up, {{lower_arm, 0.0f}}};
    add_part(mesh, *d, make_uv_sphere({ax, 0.86f, 0.0f}, 0.045f, slices / 2, slices / 4), glm::mat4(1.0f), hand);
  }
  d->joint_bounds.assign(kJointCount, Aabb{});
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    for (int k = 0; k < 4; ++k)
      if (d->weights[v][k] > 0.0f) d->joint_bounds[d->joints[v][k]].extend(mesh.vertices[v].position);
  mesh.deform = std::move(d);
  mesh.compute_bounds();
  return mesh;
}

// One rotation channel of the walk: `angle_deg(phase)` about `axis`, keyed at nine even steps.
template <typename F>
AnimationClip::Channel rotation_channel(Entity target, const glm::vec3& axis, F angle_deg) {
  AnimationClip::Channel c;
  c.target = target;
  c.path = AnimationClip::Path::Rotation;
  c.interpolation = AnimationClip::Interpolation::Linear;
  c.components = 4;
  constexpr int kKeys = 8;
  for (int k = 0; k <= kKeys; ++k) {
    const float phase = glm::two_pi<float>() * float(k) / float(kKeys);
    const glm::quat q = glm::angleAxis(glm::radians(angle_deg(phase)), axis);
    c.times.push_back(kWalkPeriod * float(k) / float(kKeys));
    c.values.insert(c.values.end(), {q.x, q.y, q.z, q.w});
  }
  return c;
}

std::shared_ptr<const AnimationClip> make_walk_clip(const std::array<Entity, kJointCount>& j) {
  auto clip = std::make_shared<AnimationClip>();
  clip->name = "walk";
  clip->duration = kWalkPeriod;
  const glm::vec3 x(1.0f, 0.0f, 0.0f), y(0.0f, 1.0f, 0.0f);
  // A negative angle about +x swings a hanging limb forward (+z).
  auto& ch = clip->channels;
  ch.push_back(rotation_channel(j[kLeftUpperLeg], x, [](float p) { return -30.0f * std::sin(p); }));
  ch.push_back(rotation_channel(j[kRightUpperLeg], x, [](float p) { return 30.0f * std::sin(p); }));
  // Knees bend while their leg swings through.
  ch.push_back(rotation_channel(j[kLeftLowerLeg], x, [](float p) { return 5.0f + 40.0f * std::max(0.0f, std::cos(p)); }));
  ch.push_back(rotation_channel(j[kRightLowerLeg], x, [](float p) { return 5.0f + 40.0f * std::max(0.0f, -std::cos(p)); }));
  ch.push_back(rotation_channel(j[kLeftUpperArm], x, [](float p) { return 25.0f * std::sin(p); }));
  ch.push_back(rotation_channel(j[kRightUpperArm], x, [](float p) { return -25.0f * std::sin(p); }));
  ch.push_back(rotation_channel(j[kLeftLowerArm], x, [](float p) { return -15.0f - 10.0f * std::sin(p); }));
  ch.push_back(rotation_channel(j[kRightLowerArm], x, [](float p) { return -15.0f + 10.0f * std::sin(p); }));
  ch.push_back(rotation_channel(j[kSpine], y, [](float p) { return 6.0f * std::sin(p); }));
  ch.push_back(rotation_channel(j[kChest], y, [](float p) { return 4.0f * std::sin(p); }));
  return clip;
}

}  // namespace

Entity add_walking_figure(Scene& scene, const glm::vec3& position, float phase,
                          const std::shared_ptr<const MeshData>& mesh, const std::string& name) {
  Registry& r = scene.registry;
  const Entity root = r.create();
  r.emplace<Name>(root, Name{name});
  Transform root_transform;
  root_transform.translation = position;
  r.emplace<Transform>(root, root_transform);

  std::array<Entity, kJointCount> joints{};
  Skeleton skeleton;
  for (uint32_t j = 0; j < kJointCount; ++j) {
    joints[j] = r.create();
    r.emplace<Name>(joints[j], Name{name + "/" + kRest[j].name});
    Transform t;
    t.translation = kRest[j].offset;
    t.parent = kRest[j].parent < 0 ? root : joints[size_t(kRest[j].parent)];
    r.emplace<Transform>(joints[j], t);
    skeleton.joints.push_back(joints[j]);
    // Joint and mesh share the root, so the bind pose is the joint's rest placement below it.
    skeleton.inverse_bind.push_back(glm::translate(glm::mat4(1.0f), -rest_position(j)));
  }

  const Entity body = r.create();
  r.emplace<Name>(body, Name{name});
  Transform body_transform;
  body_transform.parent = root;
  r.emplace<Transform>(body, body_transform);
  r.emplace<Mesh>(body, Mesh{mesh});
  Material material;
  material.base_color = {0.62f, 0.5f, 0.42f, 1.0f};
  r.emplace<Material>(body, material);
  r.emplace<ShadowCaster>(body);
  r.emplace<Skeleton>(body, std::move(skeleton));

  AnimationPlayer player;
  player.clip = make_walk_clip(joints);
  player.phase = phase;
  r.emplace<AnimationPlayer>(root, std::move(player));
  return root;
}

Entity add_walking_figure(Scene& scene, const glm::vec3& position, float phase, uint32_t tessellation,
                          const std::string& name) {
  return add_walking_figure(scene, position, phase, std::make_shared<const MeshData>(build_figure_mesh(tessellation)), name);
}

std::unique_ptr<Scene> build_character_crowd(uint32_t count) {
  auto scene = std::make_unique<Scene>();
  scene->name = "characters";
  Registry& r = scene->registry;
  const uint32_t side = std::max(1u, uint32_t(std::ceil(std::sqrt(double(count)))));
  const float spacing = 2.0f;
  const float half = 0.5f * spacing * float(side) + 6.0f;
  const Entity ground = r.create();
  MeshData ground_mesh = make_ground(half, half, 0.0f, 8);
  ground_mesh.name = "ground";
  r.emplace<Name>(ground, Name{"ground"});
  r.emplace<Transform>(ground);
  r.emplace<Mesh>(ground, Mesh{std::make_shared<const MeshData>(std::move(ground_mesh))});
  Material ground_material;
  ground_material.base_color = {0.55f, 0.55f, 0.52f, 1.0f};
  r.emplace<Material>(ground, ground_material);
  r.emplace<ShadowCaster>(ground);

  // One mesh for the whole crowd: every figure poses it with its own skeleton.
  const auto mesh = std::make_shared<const MeshData>(build_figure_mesh(32));
  glm::vec3 first(0.0f);
  for (uint32_t i = 0; i < count; ++i) {
    const float offset = 0.5f * float(side - 1);
    const glm::vec3 at{spacing * (float(i % side) - offset), 0.0f, spacing * (float(i / side) - offset)};
    if (i == 0) first = at;
    char name[32];
    std::snprintf(name, sizeof(name), "character_%03u", i);
    // Golden-ratio phases: neighbours never step in unison.
    add_walking_figure(*scene, at, kWalkPeriod * std::fmod(0.618034f * float(i), 1.0f), mesh, name);
  }

  scene->camera = r.create();
  r.emplace<Name>(scene->camera, Name{"camera"});
  r.emplace<Transform>(scene->camera);
  r.emplace<Camera>(scene->camera);
  scene->light = r.create();
  r.emplace<Name>(scene->light, Name{"sun"});
  r.emplace<DirectionalLight>(scene->light);
  const glm::vec3 sun = DirectionalLight{}.direction;
  const float reach = 0.5f * spacing * float(side);
  scene->views.push_back({"overview", {reach + 4.0f, reach + 5.0f, reach + 8.0f}, {0.0f, 0.8f, 0.0f}, sun, glm::radians(60.0f)});
  scene->views.push_back({"feet", first + glm::vec3(1.2f, 0.5f, 1.6f), first + glm::vec3(0.0f, 0.15f, 0.0f), sun,
                          glm::radians(55.0f)});
  update_world_transforms(r);
  scene->apply_view(0);
  update_world_transforms(r);
  return scene;
}

}  // namespace engine::procedural
