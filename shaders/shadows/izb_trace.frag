#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"

// Frustum trace: one fragment per (caster triangle, light texel it touches). Tests the triangle
// against every node in the texel's list and ORs the shadowed samples into the pixel's mask.
layout(push_constant) uniform Push { IzbDrawPush draw; };

vec3 fetch_grid_vertex(uint corner) {
  uint v = uint(int(indices[draw.first_index + 3u * uint(gl_PrimitiveID) + corner]) + draw.vertex_offset);
  vec3 p = vec3(vertex_floats[v * kVertexFloats], vertex_floats[v * kVertexFloats + 1u],
                vertex_floats[v * kVertexFloats + 2u]);
  return to_grid((draw.model * vec4(p, 1.0)).xyz);
}

// Separating-axis test of the texel square against the triangle (inclusive, with a little slack so
// a sample exactly on a texel border is never lost).
bool texel_touches_triangle(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float orientation) {
  const float slack = 1.0e-3;
  vec2 tmin = min(min(a.xy, b.xy), c.xy);
  vec2 tmax = max(max(a.xy, b.xy), c.xy);
  if (any(lessThan(tmax, lo - slack)) || any(greaterThan(tmin, hi + slack))) return false;
  vec2 p[3] = vec2[3](a.xy, b.xy, c.xy);
  for (int i = 0; i < 3; ++i) {
    vec2 e0 = p[i];
    vec2 e1 = p[(i + 1) % 3];
    float best = -1.0e30;
    best = max(best, orientation * edge_fn(vec2(lo.x, lo.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(hi.x, lo.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(lo.x, hi.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(hi.x, hi.y), e0, e1));
    if (best < -slack * length(e1 - e0)) return false;
  }
  return true;
}

void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  vec3 a = fetch_grid_vertex(0u);
  vec3 b = fetch_grid_vertex(1u);
  vec3 c = fetch_grid_vertex(2u);
  float area = edge_fn(c.xy, a.xy, b.xy);
  bool stats = izb_flag(IZB_FLAG_STATS);
  uint fragment = 0u, kept = 0u, tests = 0u;
  if (abs(area) > 1.0e-10 &&
      (!izb_flag(IZB_FLAG_SOFTWARE_RASTER) ||
       texel_touches_triangle(vec2(texel), vec2(texel) + 1.0, a, b, c, sign(area)))) {
    fragment = 1u;
    uint t = texel_index(texel);
    bool keep = true;
    if (izb_flag(IZB_FLAG_DEPTH_CULL)) {
      // The triangle's nearest depth over this texel, conservatively: its plane's minimum over the
      // texel square, but never nearer than its nearest vertex.
      float det = area;
      float dzdx = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) / det;
      float dzdy = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / det;
      vec2 centre = vec2(texel) + 0.5;
      float plane_min = a.z + dzdx * (centre.x - a.x) + dzdy * (centre.y - a.y) - 0.5 * (abs(dzdx) + abs(dzdy));
      float nearest = max(plane_min, min(min(a.z, b.z), c.z));
      uint far_bits = farthest[t];
      keep = far_bits != 0u && nearest < ordered_to_float(far_bits);
    } else {
      keep = heads[t] != kIzbEndOfList;
    }
    if (keep) {
      kept = 1u;
      float inv_area = 1.0 / area;
      uint full = full_mask();
      bool progressive = izb_flag(IZB_FLAG_PROGRESSIVE);
      for (uint node = heads[t]; node != kIzbEndOfList;) {
        uvec2 n = nodes[node];
        node = n.x;
        uint current = visibility_mask[n.y];
        if (progressive && current == full) continue;
        ++tests;
        uint bits = occluded_samples(n.y, a, b, c, inv_area);
        if ((bits & ~current) != 0u) atomicOr(visibility_mask[n.y], bits);
      }
    }
  }
  if (stats) {
    uint f = subgroupAdd(fragment);
    uint k = subgroupAdd(kept);
    uint s = subgroupAdd(tests);
    if (subgroupElect()) {
      if (f > 0u) atomicAdd(counters[IZB_COUNTER_FRAGMENTS], f);
      if (k > 0u) atomicAdd(counters[IZB_COUNTER_FRAGMENTS_KEPT], k);
      if (s > 0u) atomicAdd(counters[IZB_COUNTER_TRIANGLE_TESTS], s);
    }
  }
}
