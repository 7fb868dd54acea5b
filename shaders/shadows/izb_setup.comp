#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 256) in;

layout(set = 0, binding = IZB_BINDING_BOUNDS_PARTIALS, std430) readonly buffer BoundsPartials { vec4 bounds_partials[]; };

shared vec4 subgroup_bounds[256];

// Light frustum fit, step 2: reduces the fit's per-workgroup bounds, then builds an orthographic projection whose x/y window covers the reduced bounds
// plus a one-texel border (so no point sits on the grid's edge), and whose depth range spans the
// casters (from the CPU, which knows their bounds).
void main() {
  uint partials = ((params.extent.x + 31u) / 32u) * ((params.extent.y + 31u) / 32u);
  vec4 b = vec4(1.0e30, 1.0e30, -1.0e30, -1.0e30);
  for (uint i = gl_LocalInvocationIndex; i < partials; i += gl_WorkGroupSize.x) {
    vec4 p = bounds_partials[i];
    b = vec4(min(b.xy, p.xy), max(b.zw, p.zw));
  }
  b = vec4(subgroupMin(b.xy), subgroupMax(b.zw));
  if (subgroupElect()) subgroup_bounds[gl_SubgroupID] = b;
  barrier();
  if (gl_LocalInvocationIndex != 0u) return;
  for (uint i = 1u; i < gl_NumSubgroups; ++i) b = vec4(min(b.xy, subgroup_bounds[i].xy), max(b.zw, subgroup_bounds[i].zw));
  float lo_x = b.x;
  float lo_y = b.y;
  float hi_x = b.z;
  float hi_y = b.w;
  bool empty = !(hi_x >= lo_x && hi_y >= lo_y);
  if (empty) {
    lo_x = -1.0; lo_y = -1.0; hi_x = 1.0; hi_y = 1.0;
  }
  // Square texels: the same world size on both axes keeps the μQuad coverage isotropic.
  float size = max(max(hi_x - lo_x, hi_y - lo_y), 1.0e-4);
  float res = float(izb_resolution());
  float border = 2.0 * size / res;
  size += 2.0 * border;
  vec2 center = vec2(lo_x + hi_x, lo_y + hi_y) * 0.5;
  float near_d = params.depth_range.x;
  float far_d = params.depth_range.y;
  // Orthographic: x,y -> [-1,1] over the window; depth: distance along the light, 0 at near_d.
  mat4 ortho = mat4(1.0);
  ortho[0][0] = 2.0 / size;
  ortho[1][1] = 2.0 / size;
  ortho[3][0] = -2.0 * center.x / size;
  ortho[3][1] = -2.0 * center.y / size;
  // The light view looks down -z: distance d = -z.
  ortho[2][2] = -1.0 / (far_d - near_d);
  ortho[3][2] = -near_d / (far_d - near_d);
  izb.light_view_projection = ortho * params.light_view;
  izb.grid = vec4(res, 1.0 / res, size / res, empty ? 0.0 : 1.0);
  if (spot_light()) {
    // A spot light: a square perspective grid over its cone (x, y / depth within the tangent in
    // params.light_cone.y); depth 0 at the near plane, 1 at its range, and w the light-view depth, so
    // to_grid's divide leaves rays toward the light along the depth axis.
    float t = params.light_cone.y;
    mat4 perspective = mat4(0.0);
    perspective[0][0] = 1.0 / t;
    perspective[1][1] = 1.0 / t;
    perspective[2][2] = -far_d / (far_d - near_d);
    perspective[2][3] = -1.0;
    perspective[3][2] = -far_d * near_d / (far_d - near_d);
    izb.light_view_projection = perspective * params.light_view;
    izb.grid = vec4(res, 1.0 / res, 2.0 * t / res, empty ? 0.0 : 1.0);
  }
  // The overflow fallback's indirect dispatch: the build pass raises x as pixels overflow.
  counters[IZB_COUNTER_DISPATCH + 1u] = 1u;
  counters[IZB_COUNTER_DISPATCH + 2u] = 1u;
  counters[IZB_COUNTER_HYBRID + 2u] = 1u;
  counters[IZB_COUNTER_HYBRID + 3u] = 1u;
}
