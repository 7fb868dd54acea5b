// A local light's caster triangles that reach behind its near plane (izb_triangles.glsl lists them
// apart, with their grid bounds): tested by rays in world space, as rt and the reference trace them.
// Include after izb_prelude.glsl, izb_pixel.glsl and the push constants.

// A ray (t in [0, t_max] along the unit `dir`) against a world triangle, either face (Moller-Trumbore);
// `uv` the hit's barycentrics of vertices 1 and 2.
bool ray_hits_triangle(vec3 o, vec3 dir, float t_max, vec3 v0, vec3 v1, vec3 v2, out vec2 uv) {
  vec3 e1 = v1 - v0, e2 = v2 - v0;
  vec3 pv = cross(dir, e2);
  float det = dot(e1, pv);
  uv = vec2(0.0);
  if (abs(det) < 1.0e-30) return false;
  float inv = 1.0 / det;
  vec3 tv = o - v0;
  float u = dot(tv, pv) * inv;
  if (u < 0.0 || u > 1.0) return false;
  vec3 qv = cross(tv, e1);
  float v = dot(dir, qv) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  float t = dot(e2, qv) * inv;
  uv = vec2(u, v);
  return t >= 0.0 && t <= t_max;
}

// Whether a ray from grid position `g` may meet straddler `k`: a point in front of the light shares its
// projection with its whole ray, so only within the straddler's grid bounds (where it has them).
bool straddler_in_bounds(uint k, bool projected, vec2 g) {
  uvec4 entry = floatBitsToUint(grid_triangles[3u * push.triangle_count + k]);
  return !projected || entry.y == 0u ||
         !(any(lessThan(g, unpack_straddler_bound(entry.y))) || any(greaterThan(g, unpack_straddler_bound(entry.z))));
}

// The samples of candidate `p` that the straddlers shadow. With the term written by the build and
// the trace (IZB_FLAG_DIRECT_TERM) the build asks before it gives the point a node; otherwise the
// resolve asks for the candidates the trace left lit.
uint straddler_samples(ivec2 pixel, PixelPoint p) {
  uint count = counters[IZB_COUNTER_STRADDLERS];
  if (count == 0u) return 0u;
  vec3 c[4];
  if (izb_samples() == 32u) micro_quad_corners(pixel, p, c);
  uint bits = 0u;
  for (uint s = 0u; s < izb_samples(); ++s) {
    vec3 o = izb_samples() == 32u ? micro_quad_blend(c[0], c[1], c[2], c[3], kSamplePattern[s])
                                  : shadow_ray_origin(p.position, p.normal, izb_ray_offset(p.position));
    float t_max = local_shadow_ray_length(o, params.light_position.xyz, params.light_position.w);
    if (t_max <= 0.0) continue;
    vec3 dir = normalize(params.light_position.xyz - o);
    vec4 clip = izb.light_view_projection * vec4(o, 1.0);
    bool projected = clip.w > 0.0;
    vec2 g = projected ? clip_to_grid(clip).xy : vec2(0.0);
    for (uint k = 0u; k < count; ++k) {
      // On a CPU device a lane's skipped triangle still costs its batch the ray test, unless every lane
      // skips it: each lane first scans to its next triangle in bounds, and a ray test follows only
      // where some lane found one (lavapipe, lamps 1280x720, the point light's resolve 39 -> 22 ms).
      if (izb_flag(IZB_FLAG_CPU_DEVICE)) {
        while (k < count && !straddler_in_bounds(k, projected, g)) ++k;
        if (k >= count) break;
      } else if (!straddler_in_bounds(k, projected, g)) {
        continue;
      }
      uint t = floatBitsToUint(grid_triangles[3u * push.triangle_count + k].x);
      vec2 uv;
      if (!ray_hits_triangle(o, dir, t_max, casters[t].p0.xyz, casters[t].p1.xyz, casters[t].p2.xyz, uv)) continue;
      CasterAlpha ca = load_caster_alpha(t);
      if (izb_flag(IZB_FLAG_ALPHA) && ca.threshold != 0u &&
          !material_alpha_kept(ca.texture, ca.threshold, (1.0 - uv.x - uv.y) * ca.uv0 + uv.x * ca.uv1 + uv.y * ca.uv2))
        continue;
      bits |= 1u << s;
      break;
    }
  }
  return bits;
}
