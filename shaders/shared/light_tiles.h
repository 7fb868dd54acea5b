// A local light's tile lists (shaders/shadows/light_tiles.glsl), shared by C++ and GLSL: the 8x8
// tiles of pixels that each of a point light's six cube-face cones (or a spot light's one cone)
// reaches, so that a pass per face runs a workgroup per tile of its list instead of over the whole
// frame. In the lists' buffer, list f (a point light's faces in the order +x, -x, +y, -y, +z, -z; a
// spot light's one list is 0) holds its tile count and its indirect dispatch (x, y, z: rows of
// kLightTileRow workgroups) in the words [4f, 4f + 4), and its tiles (ty * light_tiles_x + tx) from
// word kLightTilesAt + f * light_tiles(width, height).
#ifndef LIGHT_TILES_H
#define LIGHT_TILES_H
#include "shared_prelude.h"

SHARED_BEGIN

SHARED_CONST uint kLightTilesAt = 32u;
SHARED_CONST uint kLightTileBlock = 32u;   // pixels a side of a GPU's listing workgroup (4x4 tiles)
SHARED_CONST uint kLightTileRow = 32768u;  // workgroups a row of a list's dispatch (the portable limit is 65535)
SHARED_INLINE uint light_tiles_x(uint width) { return (width + 7u) / 8u; }
SHARED_INLINE uint light_tiles(uint width, uint height) { return light_tiles_x(width) * ((height + 7u) / 8u); }
SHARED_INLINE uint light_tile_words(uint width, uint height) { return kLightTilesAt + 6u * light_tiles(width, height); }
// Pixels a side of a listing workgroup of 16x16 threads: a GPU's takes a 2x2 of pixels a thread, a CPU
// device's a tile a thread (light_tiles.glsl).
SHARED_INLINE uint light_tile_listing_block(bool cpu_device) { return cpu_device ? 16u * 8u : kLightTileBlock; }

SHARED_END
#endif
