// Mesh deformation (engine/core/skinning.hpp): the arithmetic skinning.comp runs on the GPU and
// engine::deform_vertices runs on the CPU for the reference, written once so both round alike
// (SHARED_PRECISE: no fused multiply-adds), and the skinning pass's bindings.
#ifndef SKINNING_H
#define SKINNING_H
#include "shared_prelude.h"

SHARED_BEGIN

// One deformed entity's dispatch. Vertices are engine::Vertex (kVertexFloats floats); the deform data
// buffer holds, per deformable mesh, kSkinWordsPerVertex words a vertex (4 joint indices, then 4
// weights as float bits) and then 6 floats per vertex per morph target (position delta, normal delta);
// the pose buffer holds the frame's joint matrices (16 floats each, column-major) and morph weights.
struct SkinningPush {
  uint rest_vertex;    // first vertex of the mesh's rest copy
  uint target_vertex;  // first vertex of the entity's own copy, which this pass overwrites
  uint vertex_count;
  uint skin_word;      // first word of the skin data in the deform data buffer, or kNoSkin
  uint morph_word;     // first word of the morph deltas
  uint target_count;   // morph targets (0: none)
  uint joint_float;    // first float of the joint matrices in the pose buffer
  uint weight_float;   // first float of the morph weights in the pose buffer
};

SHARED_CONST uint kNoSkin = 0xffffffffu;
SHARED_CONST uint kSkinWordsPerVertex = 8u;
SHARED_CONST uint kMorphFloatsPerVertex = 6u;

SHARED_CONST uint SKINNING_BINDING_VERTICES = 0u;
SHARED_CONST uint SKINNING_BINDING_DEFORM_DATA = 1u;
SHARED_CONST uint SKINNING_BINDING_POSE = 2u;

// p + w * d: one morph target's displacement (targets added in order, 0 first).
SHARED_INLINE vec3 morph_displace(vec3 p, float w, vec3 d) {
  SHARED_PRECISE vec3 r = p + d * w;
  return r;
}

// m + w * j: one joint's share of the blended skinning matrix (joints added in order, 0 first; a
// joint of weight 0 is skipped on both sides).
SHARED_INLINE mat4 blend_joint(SHARED_IN(mat4) m, SHARED_IN(mat4) j, float w) {
  SHARED_PRECISE mat4 r = m + j * w;
  return r;
}

// The blended matrix applied to a point: columns scaled and added in order.
SHARED_INLINE vec3 skin_point(SHARED_IN(mat4) m, vec3 p) {
  SHARED_PRECISE vec3 r = vec3(m[0]) * p.x;
  r = r + vec3(m[1]) * p.y;
  r = r + vec3(m[2]) * p.z;
  r = r + vec3(m[3]);
  return r;
}

// ... and to a direction (normals; not renormalised here).
SHARED_INLINE vec3 skin_direction(SHARED_IN(mat4) m, vec3 n) {
  SHARED_PRECISE vec3 r = vec3(m[0]) * n.x;
  r = r + vec3(m[1]) * n.y;
  r = r + vec3(m[2]) * n.z;
  return r;
}

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::SkinningPush) == 32);
#endif
#endif
