// The module's host-facing passes: host images -> the module's per-pixel inputs, the module's term ->
// the host's output image, and host mesh buffers -> the module's geometry. Shared by C++ and GLSL.
#ifndef HOST_H
#define HOST_H
#include "shared_prelude.h"

SHARED_BEGIN

// HostInputs::flags
SHARED_CONST uint HOST_REVERSED_Z = 1u;           // host depth: 1 near, 0 far
SHARED_CONST uint HOST_HAS_GEOMETRIC = 2u;        // a geometric-normal image is bound
SHARED_CONST uint HOST_FACING_IN_ALPHA = 4u;      // its alpha holds the light-facing decision
SHARED_CONST uint HOST_HAS_OFFSET = 8u;           // a terminator-offset image is bound
SHARED_CONST uint HOST_HAS_RECEIVER_MASK = 16u;   // a receiver-mask image is bound
SHARED_CONST uint HOST_CLEAR_OVERLAY = 32u;       // a debug view draws this frame: clear the overlay first
// Per normal image (shifted by HOST_NORMAL_SHIFT for the shading normal, HOST_GEOMETRIC_SHIFT for the
// geometric one): encoding and space bits.
SHARED_CONST uint HOST_NORMAL_OCTAHEDRAL = 1u;
SHARED_CONST uint HOST_NORMAL_VIEW_SPACE = 2u;
SHARED_CONST uint HOST_NORMAL_AS_GIVEN = 4u;      // unit and facing the camera already: no renormalize, no flip
SHARED_CONST uint HOST_NORMAL_SHIFT = 8u;
SHARED_CONST uint HOST_GEOMETRIC_SHIFT = 12u;

struct HostInputs {
  mat4 inverse_view_projection;  // module NDC (y down, reversed depth) -> world
  mat4 view_to_world;            // rotates view-space normals into world space
  vec4 camera_position;          // xyz; w: the host depth's step (UNORM), 0 for a float format
  vec4 light_direction;          // xyz: travel direction
  vec4 normal_scale_bias;        // x scale, y bias (shading normal); z scale, w bias (geometric)
  uvec4 extent;                  // x, y: size; z: flags (HOST_*); w: receiver-mask channel
};

SHARED_CONST uint HOST_INPUTS_BINDING_PARAMS = 0u;
SHARED_CONST uint HOST_INPUTS_BINDING_DEPTH = 1u;
SHARED_CONST uint HOST_INPUTS_BINDING_NORMAL = 2u;
SHARED_CONST uint HOST_INPUTS_BINDING_GEOMETRIC = 3u;
SHARED_CONST uint HOST_INPUTS_BINDING_OFFSET = 4u;
SHARED_CONST uint HOST_INPUTS_BINDING_RECEIVER = 5u;
SHARED_CONST uint HOST_INPUTS_BINDING_WORLD_POSITION = 6u;
SHARED_CONST uint HOST_INPUTS_BINDING_GEOMETRIC_OUT = 7u;
SHARED_CONST uint HOST_INPUTS_BINDING_ALBEDO_OUT = 8u;
SHARED_CONST uint HOST_INPUTS_BINDING_TERM_OUT = 9u;     // cleared to 1 (lit)
SHARED_CONST uint HOST_INPUTS_BINDING_OVERLAY_OUT = 10u; // cleared to 0 with HOST_CLEAR_OVERLAY

SHARED_CONST uint HOST_OUTPUT_BINDING_TERM = 0u;
SHARED_CONST uint HOST_OUTPUT_BINDING_OVERLAY = 1u;
SHARED_CONST uint HOST_OUTPUT_BINDING_OUT = 2u;
SHARED_CONST uint HOST_OUTPUT_BINDING_OVERLAY_OUT = 3u;
// The output pass's specialization constant 0: what it writes besides the term.
SHARED_CONST uint HOST_OUTPUT_COPY_OVERLAY = 1u;   // the host's overlay from the module's
SHARED_CONST uint HOST_OUTPUT_ZERO_OVERLAY = 2u;   // the host's overlay as 0 (no debug view drew)
SHARED_CONST uint HOST_OUTPUT_ALL_LIT = 4u;        // the host's output as 1 (no technique ran)
SHARED_CONST uint HOST_OUTPUT_OCCLUSION = 8u;      // OutputTerm::Occlusion: 1 where the light does not reach or face
SHARED_CONST uint HOST_OUTPUT_UNREACHED = 16u;     // the term of a light that reaches no point of the view: 0 covered, else 1
SHARED_CONST uint HOST_OUTPUT_BINDING_WORLD_POSITION = 4u;    // the shading points the passes read
SHARED_CONST uint HOST_OUTPUT_BINDING_GEOMETRIC_NORMAL = 5u;
// The output pass's workgroup: HOST_OUTPUT_GROUP_X x HOST_OUTPUT_GROUP_Y threads over a square block of
// HOST_OUTPUT_BLOCK pixels a side, each thread storing one pixel of every row of threads' span in turn
// (so that a warp's stores fall on whole rows of pixels).
SHARED_CONST uint HOST_OUTPUT_GROUP_X = 32u;
SHARED_CONST uint HOST_OUTPUT_GROUP_Y = 8u;
SHARED_CONST uint HOST_OUTPUT_BLOCK = 32u;
// The light the term is for (HostOutputPush::extent.z).
SHARED_CONST uint HOST_OUTPUT_LIGHT_DIRECTIONAL = 0u;
SHARED_CONST uint HOST_OUTPUT_LIGHT_SPOT = 1u;
SHARED_CONST uint HOST_OUTPUT_LIGHT_POINT = 2u;
struct HostOutputPush {
  uvec4 extent;          // x, y: size; z: HOST_OUTPUT_LIGHT_*
  vec4 light_position;   // xyz: as the passes take it (relative to the frame's origin); w: range
  vec4 light_direction;  // xyz: a spot light's unit axis; w: its outer-cone cosine
};

// Mesh import: one thread per vertex (positions, uvs) or per index.
struct MeshImportPush {
  uint src_word;      // first word of the host data (byte offset / 4)
  uint stride_words;  // between elements
  uint count;         // vertices or indices
  uint dst_first;     // first vertex / index in the module's buffers
  uint uv_word;       // vertices: first uv word; kNoUv: none
  uint uv_stride_words;
  uint mode;          // MESH_IMPORT_*
  uint pad;
};
SHARED_CONST uint MESH_IMPORT_VERTICES = 0u;
SHARED_CONST uint MESH_IMPORT_INDICES_32 = 1u;
SHARED_CONST uint MESH_IMPORT_INDICES_16 = 2u;
// Bounds of the positions (src_word, stride_words, count as for vertices) into MESH_IMPORT_BINDING_BOUNDS:
// min xyz then max xyz, as mesh_bounds_key encodes them; the buffer starts at kMeshBoundsEmpty.
SHARED_CONST uint MESH_IMPORT_BOUNDS = 3u;
// Positions only (a deformed instance's, Instance::deformed): src_word, stride_words, count and dst_first
// as for vertices; the stored normal and uv are left as they are.
SHARED_CONST uint MESH_IMPORT_POSITIONS = 4u;
SHARED_CONST uint kNoUv = 0xffffffffu;
SHARED_CONST uint MESH_IMPORT_BINDING_SOURCE = 0u;  // host positions or indices
SHARED_CONST uint MESH_IMPORT_BINDING_UVS = 1u;
SHARED_CONST uint MESH_IMPORT_BINDING_VERTICES = 2u;
SHARED_CONST uint MESH_IMPORT_BINDING_INDICES = 3u;
SHARED_CONST uint MESH_IMPORT_BINDING_BOUNDS = 4u;
// A float as a uint whose unsigned order is the float's order (negative floats: every bit flipped;
// the others: the sign bit set), so atomic min and max on the keys are min and max on the floats.
SHARED_INLINE uint mesh_bounds_key(uint float_bits) {
  return (float_bits & 0x80000000u) != 0u ? ~float_bits : float_bits | 0x80000000u;
}
SHARED_INLINE uint mesh_bounds_float_bits(uint key) {
  return (key & 0x80000000u) != 0u ? key & 0x7fffffffu : ~key;
}
SHARED_CONST uint kMeshBoundsEmptyMin = 0xffffffffu;  // the min keys' start: above every key
SHARED_CONST uint kMeshBoundsEmptyMax = 0u;           // the max keys' start: below every key

// Texture import: one thread per texel, into the material-texture words (shared/material.h).
struct TextureImportPush {
  uint first_word;
  uint width;
  uint height;
  uint alpha_from_red;  // R8 textures: alpha = r
};
SHARED_CONST uint TEXTURE_IMPORT_BINDING_SOURCE = 0u;
SHARED_CONST uint TEXTURE_IMPORT_BINDING_WORDS = 1u;

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::HostInputs) == 2 * 64 + 4 * 16);
static_assert(sizeof(gpu_shared::MeshImportPush) == 32);
static_assert(sizeof(gpu_shared::HostOutputPush) == 48);
static_assert(sizeof(gpu_shared::TextureImportPush) == 16);
#endif
#endif
