#version 460
#extension GL_GOOGLE_include_directive : require
#include "host.h"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { MeshImportPush push; };
layout(std430, set = 0, binding = MESH_IMPORT_BINDING_SOURCE) readonly buffer Source { uint source[]; };
layout(std430, set = 0, binding = MESH_IMPORT_BINDING_UVS) readonly buffer Uvs { uint uvs[]; };
layout(std430, set = 0, binding = MESH_IMPORT_BINDING_VERTICES) writeonly buffer Vertices { float vertices[]; };
layout(std430, set = 0, binding = MESH_IMPORT_BINDING_INDICES) writeonly buffer Indices { uint indices[]; };
layout(std430, set = 0, binding = MESH_IMPORT_BINDING_BOUNDS) buffer Bounds { uint bounds[6]; };

shared uint group_bounds[6];

// MESH_IMPORT_BOUNDS: min and max of the positions as order-preserving keys (mesh_bounds_key), first
// over the workgroup in shared memory, then one atomic per key and workgroup into the buffer. Exact:
// a min or max only picks one of the inputs.
void import_bounds() {
  uint lane = gl_LocalInvocationIndex;
  if (lane < 6u) group_bounds[lane] = lane < 3u ? kMeshBoundsEmptyMin : kMeshBoundsEmptyMax;
  barrier();
  uint i = gl_GlobalInvocationID.x;
  if (i < push.count) {
    uint src = push.src_word + i * push.stride_words;
    for (uint c = 0u; c < 3u; ++c) {
      uint key = mesh_bounds_key(source[src + c]);
      atomicMin(group_bounds[c], key);
      atomicMax(group_bounds[3u + c], key);
    }
  }
  barrier();
  if (lane < 3u) atomicMin(bounds[lane], group_bounds[lane]);
  else if (lane < 6u) atomicMax(bounds[lane], group_bounds[lane]);
}

// A host mesh into the module's buffers: positions (and uvs) into the engine vertex layout (8 floats:
// position, normal, uv; the normal is unused by the shadow passes and left 0), indices widened to 32 bits.
// MESH_IMPORT_POSITIONS rewrites the positions alone (a deformed instance's slot, its uvs kept).
void main() {
  // A push constant: the same for the whole dispatch, so the barriers inside stay in uniform control flow.
  if (push.mode == MESH_IMPORT_BOUNDS) {
    import_bounds();
    return;
  }
  uint i = gl_GlobalInvocationID.x;
  if (i >= push.count) return;
  if (push.mode == MESH_IMPORT_POSITIONS) {
    uint src = push.src_word + i * push.stride_words;
    uint dst = (push.dst_first + i) * 8u;
    for (uint c = 0u; c < 3u; ++c) vertices[dst + c] = uintBitsToFloat(source[src + c]);
  } else if (push.mode == MESH_IMPORT_VERTICES) {
    uint src = push.src_word + i * push.stride_words;
    uint dst = (push.dst_first + i) * 8u;
    for (uint c = 0u; c < 3u; ++c) vertices[dst + c] = uintBitsToFloat(source[src + c]);
    for (uint c = 3u; c < 6u; ++c) vertices[dst + c] = 0.0;
    if (push.uv_word != kNoUv) {
      uint uv = push.uv_word + i * push.uv_stride_words;
      vertices[dst + 6u] = uintBitsToFloat(uvs[uv]);
      vertices[dst + 7u] = uintBitsToFloat(uvs[uv + 1u]);
    } else {
      vertices[dst + 6u] = 0.0;
      vertices[dst + 7u] = 0.0;
    }
  } else if (push.mode == MESH_IMPORT_INDICES_32) {
    indices[push.dst_first + i] = source[push.src_word + i];
  } else {
    // 16-bit indices: two per word, the first in the low half (little-endian). src_word is the word of
    // the first index; an odd start is carried in stride_words (0 or 1 half).
    uint half_index = push.stride_words + i;
    uint word = source[push.src_word + half_index / 2u];
    indices[push.dst_first + i] = (half_index & 1u) != 0u ? word >> 16u : word & 0xffffu;
  }
}
