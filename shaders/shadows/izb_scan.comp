#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 256) in;

layout(push_constant) uniform Push { IzbComputePush push; };

shared uint subgroup_sums[256];

// Exclusive prefix sum across the workgroup of one value per thread; `total` gets the sum.
uint workgroup_exclusive_add(uint value, out uint total) {
  uint inclusive = subgroupInclusiveAdd(value);
  if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) subgroup_sums[gl_SubgroupID] = inclusive;
  barrier();
  uint before = 0u;
  total = 0u;
  for (uint i = 0u; i < gl_NumSubgroups; ++i) {
    if (i < gl_SubgroupID) before += subgroup_sums[i];
    total += subgroup_sums[i];
  }
  barrier();
  return before + inclusive - value;
}

// Sorted lists (counting sort), step 2: the exclusive prefix sum of the texels' node counts, in blocks
// of kIzbScanBlock texels (push.mode 0: within blocks, 1: over block sums in one workgroup, 2: block
// offsets added), leaving each list's first node in heads and a copy in the fill cursors. The block
// sums live in the fill cursors' buffer after its texels (izb.h).
void main() {
  uint texels = izb_resolution() * izb_resolution();
  uint blocks = (texels + kIzbScanBlock - 1u) / kIzbScanBlock;
  uint lane = gl_LocalInvocationID.x;
  if (push.mode == 1u) {
    uint per_thread = (blocks + 255u) / 256u;
    uint first = lane * per_thread, last = min(first + per_thread, blocks);
    uint sum = 0u;
    for (uint b = first; b < last; ++b) sum += list_cursor[texels + b];
    uint total;
    uint running = workgroup_exclusive_add(sum, total);
    for (uint b = first; b < last; ++b) {
      uint value = list_cursor[texels + b];
      list_cursor[texels + b] = running;
      running += value;
    }
    return;
  }
  uint block = IZB_ROW_DISPATCH_GROUP;
  if (block >= blocks) return;  // uniform over the workgroup
  uint base = block * kIzbScanBlock + lane * 4u;
  if (push.mode == 0u) {
    uint v[4];
    uint sum = 0u;
    for (uint k = 0u; k < 4u; ++k) {
      v[k] = base + k < texels ? list_counts[base + k] : 0u;
      sum += v[k];
    }
    uint total;
    uint running = workgroup_exclusive_add(sum, total);
    for (uint k = 0u; k < 4u; ++k) {
      if (base + k < texels) heads[base + k] = running;
      running += v[k];
    }
    if (lane == 0u) list_cursor[texels + block] = total;
    return;
  }
  uint offset = list_cursor[texels + block];
  for (uint k = 0u; k < 4u; ++k) {
    if (base + k >= texels) break;
    uint first = heads[base + k] + offset;
    heads[base + k] = first;
    list_cursor[base + k] = first;
  }
}
