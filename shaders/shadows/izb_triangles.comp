#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Every caster triangle into grid space (texels, light depth) once per frame, after the light
// frustum is fitted; the CSM, both traces and the fallback read these.
void main() {
  uint t = gl_GlobalInvocationID.x;
  if (t >= push.triangle_count) return;
  grid_triangles[3u * t] = vec4(to_grid(casters[t].p0.xyz), 0.0);
  grid_triangles[3u * t + 1u] = vec4(to_grid(casters[t].p1.xyz), 0.0);
  grid_triangles[3u * t + 2u] = vec4(to_grid(casters[t].p2.xyz), 0.0);
}
