#include "collision.hpp"

#include <algorithm>
#include <cmath>

namespace walkthrough {

namespace {
// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
glm::vec3 closest_point(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = 1.0f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}
}  // namespace

void CollisionWorld::add_mesh(const engine::MeshData& mesh, const glm::mat4& world) {
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    Triangle t;
    glm::vec3* v[3] = {&t.a, &t.b, &t.c};
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const uint32_t idx = mesh.indices[i + k];
      if (idx >= mesh.vertices.size()) {
        ok = false;
        break;
      }
      *v[k] = glm::vec3(world * glm::vec4(mesh.vertices[idx].position, 1.0f));
    }
    if (ok && glm::length(glm::cross(t.b - t.a, t.c - t.a)) > 1e-10f) triangles_.push_back(t);
  }
}

CollisionWorld::Key CollisionWorld::key(int x, int y, int z) const {
  return (Key(x & 0x1fffff) << 42) | (Key(y & 0x1fffff) << 21) | Key(z & 0x1fffff);
}

glm::ivec3 CollisionWorld::cell(const glm::vec3& p) const { return glm::ivec3(glm::floor(p / cell_size_)); }

void CollisionWorld::build() {
  grid_.clear();
  for (uint32_t i = 0; i < triangles_.size(); ++i) {
    const Triangle& t = triangles_[i];
    const glm::ivec3 lo = cell(glm::min(t.a, glm::min(t.b, t.c)));
    const glm::ivec3 hi = cell(glm::max(t.a, glm::max(t.b, t.c)));
    for (int x = lo.x; x <= hi.x; ++x)
      for (int y = lo.y; y <= hi.y; ++y)
        for (int z = lo.z; z <= hi.z; ++z) grid_[key(x, y, z)].push_back(i);
  }
  stamp_.assign(triangles_.size(), 0);
}

template <typename Fn>
void CollisionWorld::for_candidates(const glm::vec3& lo, const glm::vec3& hi, Fn&& fn) const {
  if (++query_ == 0) {
    std::fill(stamp_.begin(), stamp_.end(), 0);
    query_ = 1;
  }
  const glm::ivec3 a = cell(lo), b = cell(hi);
  for (int x = a.x; x <= b.x; ++x)
    for (int y = a.y; y <= b.y; ++y)
      for (int z = a.z; z <= b.z; ++z) {
        auto it = grid_.find(key(x, y, z));
        if (it == grid_.end()) continue;
        for (uint32_t i : it->second) {
          if (stamp_[i] == query_) continue;
          stamp_[i] = query_;
          fn(triangles_[i]);
        }
      }
}

std::vector<CollisionWorld::Contact> CollisionWorld::resolve_sphere(glm::vec3& center, float radius) const {
  std::vector<Contact> contacts;
  for (int pass = 0; pass < 4; ++pass) {
    bool moved = false;
    const glm::vec3 r(radius);
    for_candidates(center - r, center + r, [&](const Triangle& t) {
      const glm::vec3 q = closest_point(center, t.a, t.b, t.c);
      const glm::vec3 d = center - q;
      const float dist2 = glm::dot(d, d);
      if (dist2 >= radius * radius) return;
      const float dist = std::sqrt(dist2);
      glm::vec3 n = dist > 1e-6f ? d / dist : glm::normalize(glm::cross(t.b - t.a, t.c - t.a));
      const float depth = radius - dist;
      center += n * depth;
      contacts.push_back({n, depth});
      moved = true;
    });
    if (!moved) break;
  }
  return contacts;
}

bool CollisionWorld::segment_triangle(const glm::vec3& a, const glm::vec3& b, const Triangle& t, float* tout) const {
  // Möller-Trumbore on the segment, both sides.
  const glm::vec3 dir = b - a;
  const glm::vec3 e1 = t.b - t.a, e2 = t.c - t.a;
  const glm::vec3 p = glm::cross(dir, e2);
  const float det = glm::dot(e1, p);
  if (std::abs(det) < 1e-12f) return false;
  const float inv = 1.0f / det;
  const glm::vec3 s = a - t.a;
  const float u = glm::dot(s, p) * inv;
  if (u < 0.0f || u > 1.0f) return false;
  const glm::vec3 q = glm::cross(s, e1);
  const float v = glm::dot(dir, q) * inv;
  if (v < 0.0f || u + v > 1.0f) return false;
  const float tt = glm::dot(e2, q) * inv;
  if (tt < 0.0f || tt > 1.0f) return false;
  if (tout) *tout = tt;
  return true;
}

bool CollisionWorld::segment_blocked(const glm::vec3& a, const glm::vec3& b) const {
  const float length = glm::length(b - a);
  const int steps = std::max(1, int(std::ceil(length / cell_size_)));
  for (int i = 0; i < steps; ++i) {
    const glm::vec3 p0 = glm::mix(a, b, float(i) / float(steps));
    const glm::vec3 p1 = glm::mix(a, b, float(i + 1) / float(steps));
    bool hit = false;
    for_candidates(glm::min(p0, p1), glm::max(p0, p1), [&](const Triangle& t) {
      if (!hit && segment_triangle(p0, p1, t, nullptr)) hit = true;
    });
    if (hit) return true;
  }
  return false;
}

float CollisionWorld::ray_down(const glm::vec3& from, float max_distance) const {
  const glm::vec3 to = from - glm::vec3(0.0f, max_distance, 0.0f);
  float best = -1.0f;
  const int steps = std::max(1, int(std::ceil(max_distance / cell_size_)));
  for (int i = 0; i < steps && best < 0.0f; ++i) {
    const glm::vec3 p0 = glm::mix(from, to, float(i) / float(steps));
    const glm::vec3 p1 = glm::mix(from, to, float(i + 1) / float(steps));
    for_candidates(glm::min(p0, p1), glm::max(p0, p1), [&](const Triangle& t) {
      float tt = 0.0f;
      if (segment_triangle(p0, p1, t, &tt)) {
        const float d = glm::length(p0 - from) + tt * glm::length(p1 - p0);
        if (best < 0.0f || d < best) best = d;
      }
    });
  }
  return best;
}

}  // namespace walkthrough
