#version 460
#extension GL_GOOGLE_include_directive : require
#include "frame.h"
#define MATERIAL_TEXTURES_BINDING GBUFFER_BINDING_TEXTURES
#include "material_textures.glsl"
#include "shadows/terminator_offset.glsl"

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

  // Smooth terminator (shadows/terminator_offset.glsl, the include the module gives every host): the
  // offset is applied to the reconstructed shading point (shading_points.comp), which every technique
  // and the reference read.
  vec3 offset = len > 0.0 ? shadows_terminator_offset(in_world_position, p, in_corner_normals, facing) : vec3(0.0);

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
