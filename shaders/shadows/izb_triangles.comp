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
  for (uint k = 0u; k < 3u; ++k) grid_triangles[3u * t + k] = vec4(to_grid(world_triangles[3u * t + k].xyz), 0.0);
}
