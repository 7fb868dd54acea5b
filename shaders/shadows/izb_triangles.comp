#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Every caster triangle into grid space (texels, light depth) once per frame, after the light
// frustum is fitted; the CSM, both traces and the fallback read these.
// A spot light: a triangle reaching behind its near plane (where the projection folds over) or within
// twice the light's radius of it is left out of the grid (degenerate, far outside it: every pass skips
// it) and listed after the grid triangles, from 3 * triangle_count on; the resolve ray-tests it in
// world space. w: 1 / light-view depth per vertex, for perspective-correct texture coordinates.
void main() {
  uint t = gl_GlobalInvocationID.x;
  if (t >= push.triangle_count) return;
  vec3 v[3] = vec3[3](casters[t].p0.xyz, casters[t].p1.xyz, casters[t].p2.xyz);
  vec3 inv_w = vec3(1.0);
  if (spot_light()) {
    bool apart = false, behind = true;
    for (int i = 0; i < 3; ++i) {
      float d = -(params.light_view * vec4(v[i], 1.0)).z;
      apart = apart || d < params.depth_range.x || distance(v[i], params.light_position.xyz) < 2.0 * kLocalLightRadius;
      behind = behind && d < 0.0;
      inv_w[i] = 1.0 / max(d, 1.0e-30);
    }
    // No shadow ray meets a triangle wholly behind the light's plane (the cone, at most a half space,
    // lies in front) or wholly outside its range (a ray runs from a point within range to the light,
    // inside the range ball): it is left out, as degenerate, and never listed. Its bounding box bounds
    // its distance.
    vec3 lo = min(min(v[0], v[1]), v[2]), hi = max(max(v[0], v[1]), v[2]);
    vec3 nearest = clamp(params.light_position.xyz, lo, hi);
    bool unreached = behind || distance(nearest, params.light_position.xyz) > params.light_position.w;
    if (apart || unreached) {
      for (uint i = 0u; i < 3u; ++i) grid_triangles[3u * t + i] = vec4(-1.0e9, -1.0e9, 2.0, 1.0);
      if (unreached) return;
      uint k = atomicAdd(counters[IZB_COUNTER_STRADDLERS], 1u);
      grid_triangles[3u * push.triangle_count + k] = vec4(uintBitsToFloat(t), 0.0, 0.0, 0.0);
      return;
    }
  }
  for (uint i = 0u; i < 3u; ++i) grid_triangles[3u * t + i] = vec4(to_grid(v[i]), inv_w[i]);
}
