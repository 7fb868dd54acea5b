#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
// A thread a 2x2 of pixels, a workgroup a block of kIzbFaceTileBlock² pixels (4x4 of the build's
// 8x8 tiles): one atomic per face a block, not one per tile, on the six lists' counts.
layout(local_size_x = 16, local_size_y = 16) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// IZB_FLAG_FACE_TILES, run once before a point light's first face (and, on a CPU device, before a
// spot light's build, whose one list holds the tiles its cone reaches), with a face's parameters (its cone,
// params.light_cone.x, is every face's): lists the 8x8 tiles of pixels holding a covered point each
// face's cone reaches (local_light_reaches, as the build's load_local_light_pixel asks it), and
// writes the term of every point no face reaches, as each face's build would have: lit where nothing
// is covered, unlit where a covered point lies beyond the light's range. Each face's build then runs
// over its tiles alone, and writes every other pixel of them as before.
const vec3 kFaceAxes[6] = vec3[6](vec3(1.0, 0.0, 0.0), vec3(-1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, -1.0, 0.0),
                                  vec3(0.0, 0.0, 1.0), vec3(0.0, 0.0, -1.0));
const uint kBlockTiles = kIzbFaceTileBlock / 8u;  // a side

shared uint tile_faces[kBlockTiles * kBlockTiles];
shared uint face_tile_count[6];
shared uint face_base[6];

uint pixel_faces(ivec2 pixel) {
  if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return 0u;
  vec4 position = imageLoad(world_position_image, pixel);
  bool covered = position.w > 0.5;
  // local_light_reaches for each face's cone, its range and square root once: along a unit axis its
  // dot product is the component itself, exactly, so each face's verdict is the build's.
  uint faces = 0u;
  if (!point_light_face_pass()) {
    // A spot light on a CPU device: one list, of the tiles its cone reaches.
    faces = covered && local_light_reaches_point(position.xyz) ? 1u : 0u;
  } else if (covered && local_light_reaches(params.light_position.xyz, params.light_position.w, vec3(0.0), -1.0, false,
                                            position.xyz)) {
    precise vec3 from_light = position.xyz - params.light_position.xyz;
    precise float reach = params.light_cone.x * sqrt(shared_dot(from_light, from_light));
    for (uint f = 0u; f < 6u; ++f)
      if (shared_dot(from_light, kFaceAxes[f]) >= reach) faces |= 1u << f;
  }
  if (faces == 0u) imageStore(shadow_term, pixel, vec4(covered ? 0.0 : 1.0));
  return faces;
}

// A CPU device: a thread a tile, with neither shared memory nor barriers (lavapipe runs a barrier as a
// switch between a workgroup's invocations), an atomic per face a tile on the lists' counts.
void list_tile_alone() {
  uvec2 tile = gl_GlobalInvocationID.xy;
  uint tiles_x = izb_pixel_tiles_x(params.extent.x);
  if (tile.x >= tiles_x || tile.y >= (params.extent.y + 7u) / 8u) return;
  uint faces = 0u;
  for (uint k = 0u; k < 64u; ++k) faces |= pixel_faces(ivec2(tile * 8u + uvec2(k % 8u, k / 8u)));
  uint tile_index = tile.y * tiles_x + tile.x;
  uint tiles = izb_pixel_tiles(params.extent.x, params.extent.y);
  for (uint f = 0u; f < 6u; ++f) {
    if ((faces & (1u << f)) == 0u) continue;
    uint slot = atomicAdd(resolve_list[4u * f], 1u);
    atomicMax(resolve_list[4u * f + 1u], min(slot + 1u, kIzbDispatchRow));
    atomicMax(resolve_list[4u * f + 2u], slot / kIzbDispatchRow + 1u);
    atomicMax(resolve_list[4u * f + 3u], 1u);
    resolve_list[kIzbFaceTilesAt + f * tiles + slot] = tile_index;
  }
}

void main() {
  if (izb_flag(IZB_FLAG_CPU_DEVICE)) {
    list_tile_alone();
    return;
  }
  uint lane = gl_LocalInvocationIndex;
  if (lane < kBlockTiles * kBlockTiles) tile_faces[lane] = 0u;
  if (lane < 6u) face_tile_count[lane] = 0u;
  barrier();
  ivec2 first = ivec2(gl_GlobalInvocationID.xy) * 2;
  uint faces = pixel_faces(first) | pixel_faces(first + ivec2(1, 0)) | pixel_faces(first + ivec2(0, 1)) |
               pixel_faces(first + ivec2(1, 1));
  // The thread's 2x2 pixels lie in one tile of the block.
  uvec2 local_tile = gl_LocalInvocationID.xy / 4u;
  if (faces != 0u) atomicOr(tile_faces[local_tile.y * kBlockTiles + local_tile.x], faces);
  barrier();
  // A thread a tile of the block: its place in each of its faces' lists, counted in the block.
  uint tile_bits = lane < kBlockTiles * kBlockTiles ? tile_faces[lane] : 0u;
  uint place[6];
  for (uint f = 0u; f < 6u; ++f) place[f] = (tile_bits & (1u << f)) != 0u ? atomicAdd(face_tile_count[f], 1u) : 0u;
  barrier();
  // A thread a face: the block's slots in its list, and the list's indirect dispatch raised to cover
  // them (a row of kIzbDispatchRow workgroups at a time).
  if (lane < 6u && face_tile_count[lane] != 0u) {
    uint count = face_tile_count[lane];
    uint base = atomicAdd(resolve_list[4u * lane], count);
    uint last = base + count - 1u;
    // (x widens only within the first row, y only where the block's slots enter a row.)
    if (base < kIzbDispatchRow) atomicMax(resolve_list[4u * lane + 1u], min(last + 1u, kIzbDispatchRow));
    if (base == 0u || last / kIzbDispatchRow != (base - 1u) / kIzbDispatchRow)
      atomicMax(resolve_list[4u * lane + 2u], last / kIzbDispatchRow + 1u);
    if (base == 0u) resolve_list[4u * lane + 3u] = 1u;
    face_base[lane] = base;
  }
  barrier();
  if (tile_bits == 0u) return;
  uvec2 tile = gl_WorkGroupID.xy * kBlockTiles + uvec2(lane % kBlockTiles, lane / kBlockTiles);
  uint tile_index = tile.y * izb_pixel_tiles_x(params.extent.x) + tile.x;
  uint tiles = izb_pixel_tiles(params.extent.x, params.extent.y);
  for (uint f = 0u; f < 6u; ++f)
    if ((tile_bits & (1u << f)) != 0u) resolve_list[kIzbFaceTilesAt + f * tiles + face_base[f] + place[f]] = tile_index;
}
