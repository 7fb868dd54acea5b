#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Pixels whose nodes did not fit the pool: every listed caster triangle (izb_triangles.comp) is tested against the pixel's
// samples with the same exact test the trace uses, so the answer does not depend on the pool.
void main() {
  uint slot = gl_GlobalInvocationID.x;
  if (slot >= counters[IZB_COUNTER_OVERFLOW_PIXELS]) return;
  uint pixel = overflow_pixels[slot];
  uint triangle_count = listed_triangle_count();
  float gap = 1.0e30;
  uint bits = visibility_mask[pixel];
  uint full = full_mask();
  for (uint k = 0u; k < triangle_count && bits != full; ++k) {
    uint t = listed_triangle(k);
    vec3 a, b, c;
    load_grid_triangle(t, a, b, c);
    float area = edge_fn(c.xy, a.xy, b.xy);
    if (abs(area) <= 1.0e-10) continue;
    bits |= occluded_samples(pixel, load_caster_alpha(t), a, b, c, 1.0 / area, gap);
  }
  visibility_mask[pixel] = bits;
  if (izb_flag(IZB_FLAG_DIRECT_TERM) && bits != 0u) write_shadowed_term(pixel);
  if (bits != 0u) note_occluder_gap(pixel, gap);
}
