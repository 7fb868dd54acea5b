#version 460
#extension GL_GOOGLE_include_directive : require
#include "izb.h"
#include "csm.h"

layout(constant_id = 0) const uint kTest = CSM_TEST_BARYCENTRIC;
layout(location = 0) flat in vec3 in_a;
layout(location = 1) flat in vec3 in_b;
layout(location = 2) flat in vec3 in_c;

float edge_fn(vec2 p, vec2 a, vec2 b) { return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x); }

// Keeps a fragment only where its triangle covers the whole texel, and writes the triangle's
// farthest depth over the texel (its plane's maximum over the four corners).
void main() {
  vec2 lo = floor(gl_FragCoord.xy);
  vec2 corners[4] = vec2[4](lo, lo + vec2(1, 0), lo + vec2(0, 1), lo + vec2(1, 1));
  float area = edge_fn(in_c.xy, in_a.xy, in_b.xy);
  if (abs(area) < 1.0e-10) discard;
  float far_depth = -1.0e30;
  if (kTest == CSM_TEST_HERTEL) {
    // Hertel et al.: the texel centre at least the circumscribed radius inside every edge.
    vec2 centre = lo + 0.5;
    vec2 p[3] = vec2[3](in_a.xy, in_b.xy, in_c.xy);
    for (int i = 0; i < 3; ++i) {
      vec2 e0 = p[i];
      vec2 e1 = p[(i + 1) % 3];
      float distance_in = sign(area) * edge_fn(centre, e0, e1) / length(e1 - e0);
      if (distance_in < 0.70710678 + kCsmDistanceSlack) discard;
    }
  }
  for (int i = 0; i < 4; ++i) {
    float w0 = edge_fn(corners[i], in_b.xy, in_c.xy) / area;
    float w1 = edge_fn(corners[i], in_c.xy, in_a.xy) / area;
    float w2 = 1.0 - w0 - w1;
    if (kTest == CSM_TEST_BARYCENTRIC && (w0 < kCsmBarycentricSlack || w1 < kCsmBarycentricSlack || w2 < kCsmBarycentricSlack))
      discard;
    far_depth = max(far_depth, w0 * in_a.z + w1 * in_b.z + w2 * in_c.z);
  }
  gl_FragDepth = clamp(far_depth, 0.0, 1.0);
}
