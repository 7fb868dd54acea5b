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
#else
#define SHARED_BEGIN
#define SHARED_END
#define SHARED_INLINE
#define SHARED_CONST const
#define SHARED_IN(T) T
// No fused multiply-adds in what it qualifies: a GPU's compiler may fuse where the CPU (the Embree
// reference, built without FMA) rounds twice, and the shared formulas must round alike on both.
#define SHARED_PRECISE precise
#endif
#endif
