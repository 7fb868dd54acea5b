// Lets one header declare structs, constants and small functions for both C++ and GLSL.
// In C++ the declarations land in namespace `gpu_shared` with GLM types standing in for GLSL's.
#ifndef SHARED_PRELUDE_H
#define SHARED_PRELUDE_H
#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
#define SHARED_BEGIN            \
  namespace gpu_shared {        \
  using namespace glm;          \
  using uint = uint32_t;
#define SHARED_END }
#define SHARED_INLINE inline
#define SHARED_CONST inline constexpr
#define SHARED_IN(T) const T&
#define SHARED_PRECISE
namespace gpu_shared {
// The CPU's IEEE quotient and matrix product, for the shared formulas (GLSL's counterparts below).
template <typename T, typename S>
inline T shared_divide(const T& a, const S& b) { return a / b; }
inline glm::vec4 shared_transform(const glm::mat4& m, const glm::vec4& v) {
  return m[0] * v.x + m[1] * v.y + m[2] * v.z + m[3] * v.w;
}
inline float shared_dot(const glm::vec3& a, const glm::vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
}  // namespace gpu_shared
#else
#define SHARED_BEGIN
#define SHARED_END
#define SHARED_INLINE
#define SHARED_CONST const
#define SHARED_IN(T) T
// No fused multiply-adds in what it qualifies: a GPU's compiler may fuse where the CPU (the Embree
// reference, built without FMA) rounds twice, and the shared formulas must round alike on both.
#define SHARED_PRECISE precise
// GLSL lets a division be off by 2.5 ulp (GPUs multiply by an approximate reciprocal), where the CPU
// rounds the exact quotient. The exact remainder a - q b (Dekker's product, since a CPU device may not
// fuse fma()) corrects q to the correctly rounded quotient (barring overflow and near-ties), so the
// shared formulas divide alike on both.
float shared_divide(float a, float b) {
  precise float q = a / b;
  precise float q_split = 4097.0 * q;
  precise float q_high = q_split - (q_split - q);
  precise float q_low = q - q_high;
  precise float b_split = 4097.0 * b;
  precise float b_high = b_split - (b_split - b);
  precise float b_low = b - b_high;
  precise float product = q * b;
  precise float product_error = ((q_high * b_high - product) + q_high * b_low + q_low * b_high) + q_low * b_low;
  precise float remainder = (a - product) - product_error;
  precise float quotient = q + remainder / b;
  return quotient;
}
vec2 shared_divide(vec2 a, vec2 b) { return vec2(shared_divide(a.x, b.x), shared_divide(a.y, b.y)); }
vec3 shared_divide(vec3 a, float b) {
  return vec3(shared_divide(a.x, b), shared_divide(a.y, b), shared_divide(a.z, b));
}
// The matrix product and dot product in GLM's order (a driver may sum OpMatrixTimesVector's terms in any order).
vec4 shared_transform(mat4 m, vec4 v) {
  precise vec4 product = m[0] * v.x + m[1] * v.y + m[2] * v.z + m[3] * v.w;
  return product;
}
float shared_dot(vec3 a, vec3 b) {
  precise float d = a.x * b.x + a.y * b.y + a.z * b.z;
  return d;
}
#endif
#endif
