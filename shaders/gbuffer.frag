#version 460
#extension GL_GOOGLE_include_directive : require
#include "frame.h"
#define MATERIAL_TEXTURES_BINDING GBUFFER_BINDING_TEXTURES
#include "material_textures.glsl"

layout(set = 0, binding = GBUFFER_BINDING_FRAME) uniform Frame { FrameUniforms frame; };
layout(push_constant) uniform Push { DrawPush draw; };

layout(location = 0) in vec3 in_world_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in vec3 in_corners[3];         // gbuffer.vert: the triangle, in world space
layout(location = 6) flat in vec3 in_corner_normals[3];

layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_geometric_normal;
layout(location = 3) out vec4 out_terminator_offset;

vec3 srgb_to_linear(vec3 c) { return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045))); }

void main() {
  uint texel = material_texel(draw.base_color_texture, in_uv);
  if (draw.alpha_threshold != 0u && !alpha_byte_kept(texel, draw.alpha_threshold)) discard;
  // The exact plane of the triangle, from its vertices: derivatives of the interpolated position
  // would be noisy, and the 32-sample footprint needs the true plane.
  vec3 p[3] = in_corners;
  vec3 geometric = cross(p[1] - p[0], p[2] - p[0]);
  float len = length(geometric);
  geometric = len > 0.0 ? geometric / len : normalize(in_normal);
  vec3 to_camera = frame.camera_position.xyz - in_world_position;
  if (dot(geometric, to_camera) < 0.0) geometric = -geometric;
  vec3 shading = normalize(in_normal);
  float facing = dot(shading, geometric) < 0.0 ? -1.0 : 1.0;
  shading *= facing;

  // Smooth terminator (Hanika 2021, "Hacking the shadow terminator"): the shading point moves to the
  // barycentric blend of its projections onto the tangent planes of the three vertex normals, where
  // it lies below them. On a tessellated curved surface this lifts it from the flat facet toward the
  // smooth surface the normals describe, so neighbouring facets no longer shadow it and the shadow
  // boundary follows the shading. Flat-shaded meshes (vertex normals = face normal) do not move.
  // The offset is applied to the reconstructed shading point (shading_points.comp), which every
  // technique and the reference read.
  vec3 offset = vec3(0.0);
  if (len > 0.0) {
    vec3 e0 = p[1] - p[0], e1 = p[2] - p[0], d = in_world_position - p[0];
    float d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1), d20 = dot(d, e0), d21 = dot(d, e1);
    float denom = d00 * d11 - d01 * d01;
    if (denom > 0.0) {
      float b1 = clamp((d11 * d20 - d01 * d21) / denom, 0.0, 1.0);
      float b2 = clamp((d00 * d21 - d01 * d20) / denom, 0.0, 1.0 - b1);
      float bary[3] = float[3](1.0 - b1 - b2, b1, b2);
      for (int k = 0; k < 3; ++k) {
        vec3 n = in_corner_normals[k];
        float n_len = length(n);
        if (n_len == 0.0) continue;
        n = facing * n / n_len;
        offset -= bary[k] * min(0.0, dot(in_world_position - p[k], n)) * n;
      }
    }
  }

  vec4 color = draw.base_color;
  if (draw.base_color_texture != kNoTexture) color.rgb *= srgb_to_linear(unpackUnorm4x8(texel).rgb);
  float receives = (draw.flags & DRAW_FLAG_RECEIVES_SHADOW) != 0u ? 1.0 : 0.0;
  out_albedo = vec4(color.rgb, receives);
  out_normal = vec4(shading, 1.0);
  // The light-facing decision every shadow technique reads (shadow_common.h, faces_light).
  bool smooth_terminator = (frame.extent.w & FRAME_FLAG_SMOOTH_TERMINATOR) != 0u;
  bool facing_light = dot(smooth_terminator ? shading : geometric, -frame.light_direction.xyz) > 0.0;
  out_geometric_normal = vec4(geometric, facing_light ? 1.0 : 0.0);
  out_terminator_offset = vec4(offset, 0.0);
}
