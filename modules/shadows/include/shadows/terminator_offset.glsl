// The smooth-terminator offset for FrameDesc::terminator_offset, for a host's G-buffer fragment shader
// (GLSL; #include it, or copy the function). Hanika 2021, "Hacking the shadow terminator": the shading
// point moves to the barycentric blend of its projections onto the tangent planes of the triangle's
// three vertex normals, where it lies below them. On a tessellated curved surface this lifts it from
// the flat facet toward the smooth surface the normals describe, so neighbouring facets no longer
// shadow it and the shadow boundary follows the shading; flat-shaded meshes (vertex normals = face
// normal) do not move.
//
//   position       the fragment's world position (interpolated)
//   corners        the triangle's world-space vertices (e.g. passed flat from the vertex stage)
//   corner_normals its world-space vertex normals, in the same order (need not be unit length)
//   facing         1, or -1 when the shading normal was flipped to face the camera (back faces)
// Returns the world-space offset to write (xyz) into the image given as FrameDesc::terminator_offset;
// 0 for a degenerate triangle.
#ifndef SHADOWS_TERMINATOR_OFFSET_GLSL
#define SHADOWS_TERMINATOR_OFFSET_GLSL
vec3 shadows_terminator_offset(vec3 position, vec3 corners[3], vec3 corner_normals[3], float facing) {
  vec3 offset = vec3(0.0);
  vec3 e0 = corners[1] - corners[0], e1 = corners[2] - corners[0], d = position - corners[0];
  float d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1), d20 = dot(d, e0), d21 = dot(d, e1);
  float denom = d00 * d11 - d01 * d01;
  if (denom > 0.0) {
    float b1 = clamp((d11 * d20 - d01 * d21) / denom, 0.0, 1.0);
    float b2 = clamp((d00 * d21 - d01 * d20) / denom, 0.0, 1.0 - b1);
    float bary[3] = float[3](1.0 - b1 - b2, b1, b2);
    for (int k = 0; k < 3; ++k) {
      vec3 n = corner_normals[k];
      float n_len = length(n);
      if (n_len == 0.0) continue;
      n = facing * n / n_len;
      offset -= bary[k] * min(0.0, dot(position - corners[k], n)) * n;
    }
  }
  return offset;
}
#endif
