#version 460
#extension GL_GOOGLE_include_directive : require
#include "frame.h"
#include "skinning.h"

// Deforms one entity's mesh for this frame: its rest vertices, morphed by the frame's weights, then
// skinned by the frame's joint matrices, into the entity's own copy of the vertices, which the
// G-buffer draws and the shadow module reads. engine::deform_vertices is the same on the CPU.
layout(local_size_x = 64) in;
layout(set = 0, binding = SKINNING_BINDING_VERTICES, std430) buffer Vertices { float vertex_floats[]; };
layout(set = 0, binding = SKINNING_BINDING_DEFORM_DATA, std430) readonly buffer DeformData { uint deform_words[]; };
layout(set = 0, binding = SKINNING_BINDING_POSE, std430) readonly buffer Pose { float pose[]; };
layout(push_constant) uniform Push { SkinningPush job; };

vec3 rest_vec3(uint v, uint first) {
  uint base = (job.rest_vertex + v) * kVertexFloats + first;
  return vec3(vertex_floats[base], vertex_floats[base + 1u], vertex_floats[base + 2u]);
}

vec3 delta(uint word) {
  return vec3(uintBitsToFloat(deform_words[word]), uintBitsToFloat(deform_words[word + 1u]),
              uintBitsToFloat(deform_words[word + 2u]));
}

mat4 joint_matrix(uint joint) {
  uint f = job.joint_float + joint * 16u;
  return mat4(pose[f], pose[f + 1u], pose[f + 2u], pose[f + 3u], pose[f + 4u], pose[f + 5u], pose[f + 6u],
              pose[f + 7u], pose[f + 8u], pose[f + 9u], pose[f + 10u], pose[f + 11u], pose[f + 12u],
              pose[f + 13u], pose[f + 14u], pose[f + 15u]);
}

void main() {
  uint v = gl_GlobalInvocationID.x;
  if (v >= job.vertex_count) return;
  vec3 p = rest_vec3(v, 0u);
  vec3 n = rest_vec3(v, 3u);
  for (uint k = 0u; k < job.target_count; ++k) {
    float w = pose[job.weight_float + k];
    uint word = job.morph_word + (k * job.vertex_count + v) * kMorphFloatsPerVertex;
    p = morph_displace(p, w, delta(word));
    n = morph_displace(n, w, delta(word + 3u));
  }
  if (job.skin_word != kNoSkin) {
    uint word = job.skin_word + v * kSkinWordsPerVertex;
    mat4 m = mat4(0.0);
    for (uint k = 0u; k < 4u; ++k) {
      float w = uintBitsToFloat(deform_words[word + 4u + k]);
      if (w != 0.0) m = blend_joint(m, joint_matrix(deform_words[word + k]), w);
    }
    p = skin_point(m, p);
    n = skin_direction(m, n);
  }
  float len = length(n);
  if (len > 0.0) n /= len;
  uint out_base = (job.target_vertex + v) * kVertexFloats;
  vertex_floats[out_base] = p.x;
  vertex_floats[out_base + 1u] = p.y;
  vertex_floats[out_base + 2u] = p.z;
  vertex_floats[out_base + 3u] = n.x;
  vertex_floats[out_base + 4u] = n.y;
  vertex_floats[out_base + 5u] = n.z;
}
