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

SHARED_CONST uint CSM_COUNTER_TEXELS = 0u;
SHARED_CONST uint CSM_COUNTER_COUNT = 4u;

SHARED_END
#endif
