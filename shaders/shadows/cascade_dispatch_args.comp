#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
layout(local_size_x = 1) in;
layout(set = 0, binding = CASCADE_ARGS_BINDING_COUNTERS) buffer Counters { uint counters[]; };

void write_args(uint at, uint groups) {
  counters[at] = groups;
  counters[at + 1u] = 1u;
  counters[at + 2u] = 1u;
}

// Turns the list lengths into indirect dispatch sizes: after the classify stage for the kernel and band
// lists, after those for the blur list.
void main() {
  write_args(CASCADE_COUNTER_DISPATCH_KERNEL, (counters[CASCADE_COUNTER_KERNEL] + CASCADE_LIST_GROUP - 1u) / CASCADE_LIST_GROUP);
  write_args(CASCADE_COUNTER_DISPATCH_BAND, (counters[CASCADE_COUNTER_BAND] + CASCADE_LIST_GROUP - 1u) / CASCADE_LIST_GROUP);
  write_args(CASCADE_COUNTER_DISPATCH_BLUR, (counters[CASCADE_COUNTER_BLUR] + CASCADE_BLUR_GROUP - 1u) / CASCADE_BLUR_GROUP);
}
