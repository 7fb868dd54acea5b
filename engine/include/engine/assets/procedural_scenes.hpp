#pragma once
// Dimensions of the procedural scenes, shared with the tests that check analytic answers.
#include <glm/glm.hpp>

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
}  // namespace contact
}  // namespace engine::procedural
