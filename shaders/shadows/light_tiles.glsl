// A local light's tile lists (light_tiles.h): which 8x8 tiles of pixels each of a point light's six
// cube-face cones (or a spot light's one cone) reaches, listed by one pass before the light's first
// face, and a face's pass run a workgroup per tile of its list. The IZB's build (izb_face_tiles.comp)
// and the shadow map's resolve (shadow_map_tiles.comp) list them so.
//
// Before including, define LIGHT_TILES_LIST as the uint array of the lists (light_tiles.h's layout).
// To list, also define LIGHT_TILES_LISTING, declare `uint light_tile_faces(ivec2 pixel)` (the lists
// that need the pixel, as bits of local_light_faces; a pass whose lists skip a pixel writes its term
// there) and run list_light_tiles with a workgroup of 16x16 (a second include after a first without
// LIGHT_TILES_LISTING adds it).
#ifndef LIGHT_TILES_GLSL
#define LIGHT_TILES_GLSL

// The face of a point light whose cube-face pyramid holds a point at `from_light` from the light: the
// axis of its largest component by magnitude (ties to the earlier axis), on the side of its sign (a
// zero to +). Exact comparisons, so every pass that asks gets the same face, and every point has one:
// each face's pass writes only its own points (its cone, point_light_face_cos_outer, holds its
// pyramid with half a degree to spare), where the cones' overlaps once had up to three faces each
// find the same point's term.
uint point_light_face_of(vec3 from_light) {
  vec3 a = abs(from_light);
  uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
  return 2u * axis + (from_light[axis] < 0.0 ? 1u : 0u);
}

// The lists a covered point at `position` needs, as bits: a spot light's (`point_faces` false, its
// cone along the unit `spot_direction` with outer cosine `cos_outer`) bit 0 where the light reaches the
// point; a point light's (`point_faces`) the bit of its face (point_light_face_of) where the point lies
// within the range.
uint local_light_faces(vec3 light_position, float range, vec3 spot_direction, float cos_outer, bool point_faces,
                       vec3 position) {
  if (!point_faces) return local_light_reaches(light_position, range, spot_direction, cos_outer, true, position) ? 1u : 0u;
  if (!local_light_reaches(light_position, range, vec3(0.0), -1.0, false, position)) return 0u;
  precise vec3 from_light = position - light_position;
  return 1u << point_light_face_of(from_light);
}

// This invocation's pixel in list `list` of a render of `extent` pixels, a workgroup of 64 a tile of
// 8x8 (the list's indirect dispatch; an 8x8 or a 64x1 workgroup, by its index); false for a workgroup
// past the list's end.
bool light_tile_pixel(uint list, uvec2 extent, out ivec2 pixel) {
  uint slot = gl_WorkGroupID.y * kLightTileRow + gl_WorkGroupID.x;
  pixel = ivec2(0);
  if (slot >= LIGHT_TILES_LIST[4u * list]) return false;
  uint tile = LIGHT_TILES_LIST[kLightTilesAt + list * light_tiles(extent.x, extent.y) + slot];
  uint tiles_x = light_tiles_x(extent.x);
  pixel = ivec2(tile % tiles_x, tile / tiles_x) * 8 + ivec2(gl_LocalInvocationIndex % 8u, gl_LocalInvocationIndex / 8u);
  return true;
}
#endif

#if defined(LIGHT_TILES_LISTING) && !defined(LIGHT_TILES_LISTING_GLSL)
#define LIGHT_TILES_LISTING_GLSL
// A CPU device: a thread a tile (a workgroup 16x16 tiles), with neither shared memory nor barriers
// (lavapipe runs a barrier as a switch between a workgroup's invocations), an atomic per list a tile
// on the lists' counts.
void list_light_tile_alone(uvec2 extent) {
  uvec2 tile = gl_GlobalInvocationID.xy;
  uint tiles_x = light_tiles_x(extent.x);
  if (tile.x >= tiles_x || tile.y >= (extent.y + 7u) / 8u) return;
  uint faces = 0u;
  for (uint k = 0u; k < 64u; ++k) faces |= light_tile_faces(ivec2(tile * 8u + uvec2(k % 8u, k / 8u)));
  uint tile_index = tile.y * tiles_x + tile.x;
  uint tiles = light_tiles(extent.x, extent.y);
  for (uint f = 0u; f < 6u; ++f) {
    if ((faces & (1u << f)) == 0u) continue;
    uint slot = atomicAdd(LIGHT_TILES_LIST[4u * f], 1u);
    atomicMax(LIGHT_TILES_LIST[4u * f + 1u], min(slot + 1u, kLightTileRow));
    atomicMax(LIGHT_TILES_LIST[4u * f + 2u], slot / kLightTileRow + 1u);
    atomicMax(LIGHT_TILES_LIST[4u * f + 3u], 1u);
    LIGHT_TILES_LIST[kLightTilesAt + f * tiles + slot] = tile_index;
  }
}

// A GPU: a thread a 2x2 of pixels, a workgroup a block of kLightTileBlock² pixels (4x4 tiles), one
// atomic per list a block, not one per tile, on the lists' counts.
const uint kLightBlockTiles = kLightTileBlock / 8u;  // a side
shared uint light_block_tile_faces[kLightBlockTiles * kLightBlockTiles];
shared uint light_block_count[6];
shared uint light_block_base[6];

void list_light_tiles_in_block(uvec2 extent) {
  uint lane = gl_LocalInvocationIndex;
  if (lane < kLightBlockTiles * kLightBlockTiles) light_block_tile_faces[lane] = 0u;
  if (lane < 6u) light_block_count[lane] = 0u;
  barrier();
  ivec2 first = ivec2(gl_GlobalInvocationID.xy) * 2;
  uint faces = light_tile_faces(first) | light_tile_faces(first + ivec2(1, 0)) | light_tile_faces(first + ivec2(0, 1)) |
               light_tile_faces(first + ivec2(1, 1));
  // The thread's 2x2 pixels lie in one tile of the block.
  uvec2 local_tile = gl_LocalInvocationID.xy / 4u;
  if (faces != 0u) atomicOr(light_block_tile_faces[local_tile.y * kLightBlockTiles + local_tile.x], faces);
  barrier();
  // A thread a tile of the block: its place in each of its lists, counted in the block.
  uint tile_bits = lane < kLightBlockTiles * kLightBlockTiles ? light_block_tile_faces[lane] : 0u;
  uint place[6];
  for (uint f = 0u; f < 6u; ++f) place[f] = (tile_bits & (1u << f)) != 0u ? atomicAdd(light_block_count[f], 1u) : 0u;
  barrier();
  // A thread a list: the block's slots in it, and its indirect dispatch raised to cover them (a row
  // of kLightTileRow workgroups at a time).
  if (lane < 6u && light_block_count[lane] != 0u) {
    uint count = light_block_count[lane];
    uint base = atomicAdd(LIGHT_TILES_LIST[4u * lane], count);
    uint last = base + count - 1u;
    // (x widens only within the first row, y only where the block's slots enter a row.)
    if (base < kLightTileRow) atomicMax(LIGHT_TILES_LIST[4u * lane + 1u], min(last + 1u, kLightTileRow));
    if (base == 0u || last / kLightTileRow != (base - 1u) / kLightTileRow)
      atomicMax(LIGHT_TILES_LIST[4u * lane + 2u], last / kLightTileRow + 1u);
    if (base == 0u) LIGHT_TILES_LIST[4u * lane + 3u] = 1u;
    light_block_base[lane] = base;
  }
  barrier();
  if (tile_bits == 0u) return;
  uvec2 tile = gl_WorkGroupID.xy * kLightBlockTiles + uvec2(lane % kLightBlockTiles, lane / kLightBlockTiles);
  uint tile_index = tile.y * light_tiles_x(extent.x) + tile.x;
  uint tiles = light_tiles(extent.x, extent.y);
  for (uint f = 0u; f < 6u; ++f)
    if ((tile_bits & (1u << f)) != 0u)
      LIGHT_TILES_LIST[kLightTilesAt + f * tiles + light_block_base[f] + place[f]] = tile_index;
}

// The lists of a render of `extent` pixels, their counts and dispatches zeroed before: a workgroup
// of 16x16 threads covers kLightTileBlock² pixels on a GPU, 16x16 tiles on a CPU device.
void list_light_tiles(bool cpu_device, uvec2 extent) {
  if (cpu_device) list_light_tile_alone(extent);
  else list_light_tiles_in_block(extent);
}
#endif
