#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/components.hpp"

namespace {

using namespace engine;

TEST(Aabb, StartsInvalidAndGrowsWithPointsAndBoxes) {
  Aabb box;
  EXPECT_FALSE(box.valid());
  box.extend(glm::vec3(1, 2, 3));
  EXPECT_TRUE(box.valid());
  box.extend(glm::vec3(-1, 5, 0));
  EXPECT_EQ(box.min, glm::vec3(-1, 2, 0));
  EXPECT_EQ(box.max, glm::vec3(1, 5, 3));
  EXPECT_EQ(box.center(), glm::vec3(0, 3.5f, 1.5f));
  EXPECT_EQ(box.extent(), glm::vec3(2, 3, 3));
  Aabb other;
  box.extend(other);  // an invalid box adds nothing
  EXPECT_EQ(box.min, glm::vec3(-1, 2, 0));
  EXPECT_FALSE(other.transformed(glm::mat4(1.0f)).valid());
}

TEST(Aabb, TransformedUsesAllCorners) {
  Aabb box;
  box.extend(glm::vec3(0, 0, 0));
  box.extend(glm::vec3(2, 1, 1));
  // 45 degrees about y: the x/z footprint grows to the rotated square's bounds.
  const glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(10, 0, 0)) *
                      glm::rotate(glm::mat4(1.0f), glm::radians(45.0f), glm::vec3(0, 1, 0));
  const Aabb t = box.transformed(m);
  const float s = std::sqrt(0.5f);
  // Corners (x,z) -> (x c + z s, -x s + z c) with c = s.
  EXPECT_NEAR(t.min.x, 10.0f, 1e-5f);
  EXPECT_NEAR(t.max.x, 10.0f + 3.0f * s, 1e-5f);
  EXPECT_NEAR(t.min.z, -2.0f * s, 1e-5f);
  EXPECT_NEAR(t.max.z, 1.0f * s, 1e-5f);
  EXPECT_NEAR(t.min.y, 0.0f, 1e-6f);
  EXPECT_NEAR(t.max.y, 1.0f, 1e-6f);

  const Aabb scaled = box.transformed(glm::scale(glm::mat4(1.0f), glm::vec3(-1, 2, 1)));
  EXPECT_NEAR(scaled.min.x, -2.0f, 1e-6f);
  EXPECT_NEAR(scaled.max.x, 0.0f, 1e-6f);
  EXPECT_NEAR(scaled.max.y, 2.0f, 1e-6f);
}

TEST(MeshData, ComputeBoundsCoversAllVerticesAndResets) {
  MeshData m;
  m.vertices = {{{1, 0, 0}, {0, 1, 0}, {0, 0}}, {{-2, 3, 1}, {0, 1, 0}, {0, 0}}, {{0, -1, 5}, {0, 1, 0}, {0, 0}}};
  m.indices = {0, 1, 2};
  m.compute_bounds();
  EXPECT_EQ(m.bounds.min, glm::vec3(-2, -1, 0));
  EXPECT_EQ(m.bounds.max, glm::vec3(1, 3, 5));
  EXPECT_EQ(m.triangle_count(), 1u);
  m.vertices.resize(1);
  m.compute_bounds();  // recomputation must not keep the old extremes
  EXPECT_EQ(m.bounds.min, glm::vec3(1, 0, 0));
  EXPECT_EQ(m.bounds.max, glm::vec3(1, 0, 0));
}

}  // namespace
