#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
layout(local_size_x = 16, local_size_y = 16) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// IZB_FLAG_FACE_TILES, run once before a point light's first face (and, on a CPU device, before a
// spot light's build, whose one list holds the tiles its cone reaches), with a face's parameters: lists
// the 8x8 tiles of pixels holding a covered point of each face (local_light_faces: within the range
// and the face's pyramid, point_light_face_of, as the build's outside_light_face asks it), and
// writes the term of every point no face reaches, as each face's build would have: lit where nothing
// is covered, unlit where a covered point lies beyond the light's range. Each face's build then runs
// over its tiles alone, and writes every other pixel of them as before.
uint light_tile_faces(ivec2 pixel) {
  if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return 0u;
  vec4 position = imageLoad(world_position_image, pixel);
  bool covered = position.w > 0.5;
  uint faces = covered ? local_light_faces(params.light_position.xyz, params.light_position.w, params.light_direction.xyz,
                                           params.light_cone.x, point_light_face_pass(), position.xyz)
                       : 0u;
  if (faces == 0u) imageStore(shadow_term, pixel, vec4(covered ? 0.0 : 1.0));
  return faces;
}
#define LIGHT_TILES_LISTING
#include "shadows/light_tiles.glsl"

void main() { list_light_tiles(izb_flag(IZB_FLAG_CPU_DEVICE), params.extent.xy); }
