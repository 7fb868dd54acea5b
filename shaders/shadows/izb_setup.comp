#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 1) in;

// Light frustum fit, step 2: an orthographic projection whose x/y window covers the reduced bounds
// plus a one-texel border (so no point sits on the grid's edge), and whose depth range spans the
// casters (from the CPU, which knows their bounds).
void main() {
  float lo_x = ordered_to_float(counters[IZB_COUNTER_BOUNDS + 0u]);
  float lo_y = ordered_to_float(counters[IZB_COUNTER_BOUNDS + 1u]);
  float hi_x = ordered_to_float(counters[IZB_COUNTER_BOUNDS + 2u]);
  float hi_y = ordered_to_float(counters[IZB_COUNTER_BOUNDS + 3u]);
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
  // The overflow fallback's indirect dispatch: the build pass raises x as pixels overflow.
  counters[IZB_COUNTER_DISPATCH + 1u] = 1u;
  counters[IZB_COUNTER_DISPATCH + 2u] = 1u;
}
