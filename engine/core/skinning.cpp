#include "engine/core/skinning.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include "shared/skinning.h"

namespace engine {

namespace {

// The key interval holding `t` (clamped to the keys): index of its first key and the fraction.
std::pair<size_t, float> key_interval(const std::vector<float>& times, float t) {
  if (times.size() < 2 || t <= times.front()) return {0, 0.0f};
  if (t >= times.back()) return {times.size() - 1, 0.0f};
  const size_t i = size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
  const float span = times[i + 1] - times[i];
  return {i, span > 0.0f ? (t - times[i]) / span : 0.0f};
}

// Channel `c`'s value at time `t` (c.components floats).
std::vector<float> sample(const AnimationClip::Channel& c, float t) {
  const size_t n = c.components;
  const bool cubic = c.interpolation == AnimationClip::Interpolation::CubicSpline;
  const size_t stride = cubic ? 3 * n : n;
  const auto value = [&](size_t key, size_t part) { return &c.values[key * stride + (cubic ? part * n : 0)]; };
  std::vector<float> out(n, 0.0f);
  if (c.times.empty() || c.values.size() < c.times.size() * stride) return out;
  const auto [i, f] = key_interval(c.times, t);
  const float* a = value(i, 1);
  if (f == 0.0f || i + 1 >= c.times.size() || c.interpolation == AnimationClip::Interpolation::Step) {
    std::copy(a, a + n, out.begin());
  } else if (cubic) {
    // glTF's Hermite spline: tangents scaled by the key interval.
    const float dt = c.times[i + 1] - c.times[i];
    const float f2 = f * f, f3 = f2 * f;
    const float* b = value(i + 1, 1);
    const float* out_tangent = value(i, 2);
    const float* in_tangent = value(i + 1, 0);
    for (size_t k = 0; k < n; ++k)
      out[k] = (2 * f3 - 3 * f2 + 1) * a[k] + (f3 - 2 * f2 + f) * dt * out_tangent[k] + (-2 * f3 + 3 * f2) * b[k] +
               (f3 - f2) * dt * in_tangent[k];
  } else if (c.path == AnimationClip::Path::Rotation) {
    const float* b = value(i + 1, 1);
    const glm::quat qa(a[3], a[0], a[1], a[2]), qb(b[3], b[0], b[1], b[2]);
    const glm::quat q = glm::slerp(qa, qb, f);
    out = {q.x, q.y, q.z, q.w};
  } else {
    const float* b = value(i + 1, 1);
    for (size_t k = 0; k < n; ++k) out[k] = a[k] + (b[k] - a[k]) * f;
  }
  return out;
}

void apply(Registry& registry, const AnimationClip::Channel& c, const std::vector<float>& v) {
  using Path = AnimationClip::Path;
  if (c.path == Path::Weights) {
    if (auto* w = registry.try_get<MorphWeights>(c.target)) {
      const size_t n = std::min(w->weights.size(), v.size());
      std::copy(v.begin(), v.begin() + std::ptrdiff_t(n), w->weights.begin());
    }
    return;
  }
  auto* t = registry.try_get<Transform>(c.target);
  if (!t || v.size() < 3) return;
  if (c.path == Path::Translation) t->translation = glm::vec3(v[0], v[1], v[2]);
  if (c.path == Path::Scale) t->scale = glm::vec3(v[0], v[1], v[2]);
  if (c.path == Path::Rotation && v.size() >= 4) {
    const glm::quat q(v[3], v[0], v[1], v[2]);
    const float len = glm::length(q);
    if (len > 0.0f) t->rotation = q / len;
  }
}

}  // namespace

void update_clip_animations(Registry& registry, float seconds) {
  registry.each<AnimationPlayer>([&](Entity, AnimationPlayer& player) {
    if (!player.clip || !player.playing) return;
    const AnimationClip& clip = *player.clip;
    float t = seconds * player.speed + player.phase;
    if (clip.duration > 0.0f) {
      t = std::fmod(t, clip.duration);
      if (t < 0.0f) t += clip.duration;
    }
    for (const auto& c : clip.channels)
      if (registry.alive(c.target)) apply(registry, c, sample(c, t));
  });
}

std::vector<glm::mat4> joint_matrices(const Registry& registry, Entity entity) {
  const auto* skeleton = registry.try_get<Skeleton>(entity);
  const auto* self = registry.try_get<Transform>(entity);
  if (!skeleton) return {};
  const glm::mat4 to_object = self ? glm::inverse(self->world) : glm::mat4(1.0f);
  std::vector<glm::mat4> out(skeleton->joints.size(), glm::mat4(1.0f));
  for (size_t j = 0; j < skeleton->joints.size(); ++j) {
    const auto* joint = registry.try_get<Transform>(skeleton->joints[j]);
    const glm::mat4 inverse_bind = j < skeleton->inverse_bind.size() ? skeleton->inverse_bind[j] : glm::mat4(1.0f);
    if (joint) out[j] = to_object * joint->world * inverse_bind;
  }
  return out;
}

void deform_vertices(const MeshData& mesh, std::span<const float> morph_weights,
                     std::span<const glm::mat4> joint_matrices, std::vector<Vertex>& out) {
  out = mesh.vertices;
  const DeformData* d = mesh.deform.get();
  if (!d) return;
  // skinning.comp's order: targets in order, then the joints of weight > 0 in order (shared/skinning.h).
  const size_t targets = std::min(morph_weights.size(), d->morph_targets.size());
  const bool skin = d->skinned() && !joint_matrices.empty();
  for (size_t v = 0; v < out.size(); ++v) {
    glm::vec3 p = out[v].position, n = out[v].normal;
    for (size_t k = 0; k < targets; ++k) {
      const MorphTarget& t = d->morph_targets[k];
      p = gpu_shared::morph_displace(p, morph_weights[k], t.position_deltas[v]);
      n = gpu_shared::morph_displace(n, morph_weights[k], t.normal_deltas.empty() ? glm::vec3(0.0f) : t.normal_deltas[v]);
    }
    if (skin) {
      glm::mat4 m(0.0f);
      for (int k = 0; k < 4; ++k) {
        const float w = d->weights[v][k];
        const uint32_t j = d->joints[v][k];
        if (w != 0.0f) m = gpu_shared::blend_joint(m, j < joint_matrices.size() ? joint_matrices[j] : glm::mat4(1.0f), w);
      }
      p = gpu_shared::skin_point(m, p);
      n = gpu_shared::skin_direction(m, n);
    }
    const float len = glm::length(n);
    out[v].position = p;
    out[v].normal = len > 0.0f ? n / len : n;
  }
}

Aabb deformed_bounds(const MeshData& mesh, std::span<const float> morph_weights,
                     std::span<const glm::mat4> joint_matrices) {
  const DeformData* d = mesh.deform.get();
  if (!d) return mesh.bounds;
  // The morph's reach: per axis, the most each weight can move a vertex either way.
  glm::vec3 low(0.0f), high(0.0f);
  for (size_t k = 0; k < std::min(morph_weights.size(), d->morph_targets.size()); ++k) {
    glm::vec3 lo(0.0f), hi(0.0f);
    for (const glm::vec3& delta : d->morph_targets[k].position_deltas) lo = glm::min(lo, delta), hi = glm::max(hi, delta);
    const float w = morph_weights[k];
    low += glm::min(lo * w, hi * w);
    high += glm::max(lo * w, hi * w);
  }
  const auto grown = [&](const Aabb& b) {
    Aabb g;
    if (b.valid()) g.extend(b.min + low), g.extend(b.max + high);
    return g;
  };
  if (!d->skinned() || joint_matrices.empty()) return grown(mesh.bounds);
  // A skinned vertex is a convex combination of its joints' transforms of it: inside the union of each
  // joint's box (of the vertices it moves) transformed by that joint.
  Aabb out;
  for (size_t j = 0; j < d->joint_bounds.size() && j < joint_matrices.size(); ++j)
    out.extend(grown(d->joint_bounds[j]).transformed(joint_matrices[j]));
  // Rounding of the blend (a few ulp of the coordinates' size): widened by a relative margin.
  if (out.valid()) {
    const glm::vec3 pad = 1e-5f * (glm::abs(out.min) + glm::abs(out.max) + out.extent()) + glm::vec3(1e-6f);
    out.min -= pad, out.max += pad;
  }
  return out;
}

std::vector<Vertex> posed_vertices(const Registry& registry, Entity entity) {
  const auto* mesh = registry.try_get<Mesh>(entity);
  if (!mesh || !mesh->data) return {};
  if (!mesh->data->deform) return mesh->data->vertices;
  std::vector<float> weights = mesh->data->deform->default_weights;
  if (const auto* w = registry.try_get<MorphWeights>(entity)) weights = w->weights;
  weights.resize(mesh->data->deform->morph_targets.size(), 0.0f);
  std::vector<glm::mat4> joints = joint_matrices(registry, entity);
  if (!joints.empty()) joints.resize(std::max<size_t>(joints.size(), mesh->data->deform->joint_count), glm::mat4(1.0f));
  std::vector<Vertex> out;
  deform_vertices(*mesh->data, weights, joints, out);
  return out;
}

}  // namespace engine
