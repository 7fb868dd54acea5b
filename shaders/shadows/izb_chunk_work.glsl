// Work on one texel of a triangle's texel box, shared by the chunk emitter (which runs a chunk
// itself when the chunk buffer is full) and the chunk workgroups. Include after izb_prelude.glsl.
layout(set = 0, binding = IZB_BINDING_CHUNKS, std430) buffer Chunks { uvec2 chunks[]; };
layout(set = 0, binding = IZB_BINDING_PAIRS, std430) buffer Pairs { uvec2 pairs[]; };
layout(set = 0, binding = IZB_BINDING_TRIANGLE_DRAW, std430) readonly buffer TriangleDraw { uint triangle_draw[]; };
layout(set = 0, binding = IZB_BINDING_DRAW_FLAGS, std430) readonly buffer DrawFlags { uint draw_flags[]; };
layout(set = 0, binding = IZB_BINDING_CSM_TEXELS, std430) buffer CsmTexels { uint csm_texels[]; };
#include "csm.h"

// The texel box [lo, hi) a triangle's grid-space bounds touch, clamped to the grid; empty when
// the triangle is degenerate or outside.
struct TexelBox {
  ivec2 lo;
  ivec2 size;
};

TexelBox triangle_texel_box(vec3 a, vec3 b, vec3 c) {
  int res = int(izb_resolution());
  TexelBox box;
  vec2 lo = floor(min(min(a.xy, b.xy), c.xy));
  vec2 hi = floor(max(max(a.xy, b.xy), c.xy)) + 1.0;
  lo = clamp(lo, vec2(0.0), vec2(res));
  hi = clamp(hi, vec2(0.0), vec2(res));
  box.lo = ivec2(lo);
  box.size = max(ivec2(hi) - box.lo, ivec2(0));
  return box;
}

uint box_texels(TexelBox box) { return uint(box.size.x) * uint(box.size.y); }

ivec2 box_texel(TexelBox box, uint i) { return box.lo + ivec2(int(i % uint(box.size.x)), int(i / uint(box.size.x))); }

// Trace: whether the triangle's (texel) pair survives the conservative touch test and the depth cull
// against the texel's farthest node. `touched` reports the touch test alone (statistics).
bool trace_pair_survives(ivec2 texel, vec3 a, vec3 b, vec3 c, float area, out bool touched) {
  vec2 lo = vec2(texel);
  touched = rect_touches_triangle(lo, lo + 1.0, a, b, c, sign(area));
  if (!touched) return false;
  if (izb_flag(IZB_FLAG_NO_DEPTH_CULL)) return true;
  float farthest_node = uintBitsToFloat(farthest[texel_index(texel)]);
  return triangle_nearest_depth(lo, lo + 1.0, a, b, c, area) < farthest_node;
}

// CSM: where the triangle fully covers the texel (Hertel's or the barycentric test, the same
// arithmetic as csm.frag), the nearest bound so far of its farthest depth over the texel.
void csm_texel(ivec2 texel, vec3 a, vec3 b, vec3 c, float area, uint test) {
  vec2 lo = vec2(texel);
  vec2 corners[4] = vec2[4](lo, lo + vec2(1, 0), lo + vec2(0, 1), lo + vec2(1, 1));
  if (test == IZB_CHUNKS_FOR_CSM_HERTEL) {
    vec2 centre = lo + 0.5;
    vec2 p[3] = vec2[3](a.xy, b.xy, c.xy);
    for (int i = 0; i < 3; ++i) {
      vec2 e0 = p[i];
      vec2 e1 = p[(i + 1) % 3];
      float distance_in = sign(area) * edge_fn(centre, e0, e1) / length(e1 - e0);
      if (distance_in < 0.70710678 + kCsmDistanceSlack) return;
    }
  }
  float far_depth = -1.0e30;
  for (int i = 0; i < 4; ++i) {
    float w0 = edge_fn(corners[i], b.xy, c.xy) / area;
    float w1 = edge_fn(corners[i], c.xy, a.xy) / area;
    float w2 = 1.0 - w0 - w1;
    if (test == IZB_CHUNKS_FOR_CSM_BARYCENTRIC &&
        (w0 < kCsmBarycentricSlack || w1 < kCsmBarycentricSlack || w2 < kCsmBarycentricSlack))
      return;
    far_depth = max(far_depth, w0 * a.z + w1 * b.z + w2 * c.z);
  }
  // Depths in [0,1]: float order is bit order.
  uint bits = floatBitsToUint(clamp(far_depth, 0.0, 1.0));
  uint index = texel_index(texel);
  if (bits < csm_texels[index]) atomicMin(csm_texels[index], bits);
}

uint chunk_counter(uint mode) { return mode == IZB_CHUNKS_FOR_TRACE ? IZB_COUNTER_CHUNKS : IZB_COUNTER_CSM_CHUNKS; }
uint chunk_records(uint mode) { return min(counters[chunk_counter(mode)], params.limits.z); }

bool triangle_wanted(uint t, uint mode) {
  return mode == IZB_CHUNKS_FOR_TRACE || (draw_flags[triangle_draw[t]] & IZB_DRAW_IN_CSM) != 0u;
}
