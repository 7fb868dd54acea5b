// The conservative shadow map pass, shared by C++ and GLSL.
#ifndef CSM_H
#define CSM_H
#include "shared_prelude.h"

SHARED_BEGIN

SHARED_CONST uint CSM_BINDING_FRAME = 0u;     // IzbFrame (light projection fitted on the GPU)
SHARED_CONST uint CSM_BINDING_COUNTERS = 1u;
SHARED_CONST uint CSM_BINDING_DEPTH = 2u;     // the CSM itself, for the coverage count

SHARED_CONST uint CSM_TEST_HERTEL = 0u;
SHARED_CONST uint CSM_TEST_BARYCENTRIC = 1u;

// A triangle covers a texel fully when all four corners have barycentrics at least this large
// (relative), or, for Hertel's test, when the centre is this much farther than the circumscribed
// radius from every edge (in texels): slack on the safe side of rounding.
SHARED_CONST float kCsmBarycentricSlack = 1.0e-5f;
SHARED_CONST float kCsmDistanceSlack = 1.0e-4f;

// The automatic per-instance CSM choice, measured on the GPU (csm_measure.comp): per instance, the
// light-space projected area of its mesh and the part of it that can fully cover texels.
SHARED_CONST uint CSM_MEASURE_BINDING_VERTICES = 0u;  // the module's vertices (engine::Vertex, 8 floats)
SHARED_CONST uint CSM_MEASURE_BINDING_INDICES = 1u;   // the module's 32-bit indices
SHARED_CONST uint CSM_MEASURE_BINDING_JOBS = 2u;      // CsmMeasureJob per measured instance
SHARED_CONST uint CSM_MEASURE_BINDING_PARTIALS = 3u;  // vec2 (projected, coverable) per job and workgroup
SHARED_CONST uint kCsmMeasureGroupSize = 64u;
struct CsmMeasureJob {
  mat4 world;
  uint first_index;
  int vertex_offset;
  uint triangle_count;
  uint pad;
};
struct CsmMeasurePush {
  mat4 to_light;       // rotation into light space (the upper 3x3 is used)
  float circumradius;  // of one CSM texel, world units
  uint groups_per_job; // workgroups along x; each job's partials are that many vec2
  uint pad0, pad1;
};

SHARED_CONST uint CSM_COUNTER_TEXELS = 0u;
SHARED_CONST uint CSM_COUNTER_COUNT = 4u;

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::CsmMeasureJob) == 80);
static_assert(sizeof(gpu_shared::CsmMeasurePush) == 80);
#endif
#endif
