#pragma once
// Random numbers that are the same on every standard library (std::uniform_real_distribution is not),
// so generated scenes, and the reference images of them, are identical everywhere.
#include <cmath>
#include <cstdint>
#include <random>

#include <glm/glm.hpp>

namespace engine::detail {

class PortableRandom {
 public:
  explicit PortableRandom(uint32_t seed) : engine_(seed) {}
  float uniform(float lo, float hi) { return lo + (hi - lo) * float(engine_() >> 8) * (1.0f / 16777216.0f); }
  int integer(int lo, int hi) { return lo + int(engine_() % uint32_t(hi - lo + 1)); }
  glm::vec3 unit_vector() {
    for (;;) {
      const glm::vec3 p{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
      const float l2 = glm::dot(p, p);
      if (l2 > 1e-4f && l2 <= 1.0f) return p / std::sqrt(l2);
    }
  }

 private:
  std::mt19937 engine_;
};

}  // namespace engine::detail
