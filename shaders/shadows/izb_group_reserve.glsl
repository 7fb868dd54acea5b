// A workgroup's appends to a counter with one atomic (atomics on one address serialize, and each
// costs its subgroup a round trip). Include after izb_prelude.glsl.

shared uint group_subgroup_offsets[256];
shared uint group_reserved_base;

// Reserves the invocation's `count` consecutive slots of counters[counter] and returns the first;
// also raises the indirect dispatch at `dispatch_at` to the counter's items (at most `capacity`) in
// workgroups of `per_group`, for the pass that reads them. Every invocation of the workgroup calls it
// together, in uniform control flow.
uint reserve_group_slots(uint counter, uint count, uint dispatch_at, uint capacity, uint per_group) {
  // A CPU device runs a workgroup's invocations one batch after another and pays for each barrier a
  // switch through all of them; its atomics are cheap (reserve_slots_raising: one a lane).
  if (gl_NumSubgroups == 1u || izb_flag(IZB_FLAG_CPU_DEVICE))
    return reserve_slots_raising(counter, count, true, dispatch_at, capacity, per_group);
  uint offset = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  barrier();  // the previous call's reads are done
  if (subgroupElect()) group_subgroup_offsets[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint sum = 0u;
    for (uint i = 0u; i < gl_NumSubgroups; ++i) {
      uint t = group_subgroup_offsets[i];
      group_subgroup_offsets[i] = sum;
      sum += t;
    }
    uint base = 0u;
    if (sum > 0u) {
      base = atomicAdd(counters[counter], sum);
      raise_row_dispatch(dispatch_at, min(base + sum, capacity), per_group);
    }
    group_reserved_base = base;
  }
  barrier();
  return group_reserved_base + group_subgroup_offsets[gl_SubgroupID] + offset;
}
