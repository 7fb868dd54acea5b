#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
layout(local_size_x = 1) in;
layout(set = 0, binding = CASCADE_BLUR_ARGS_BINDING_COUNTERS) buffer Counters { uint counters[]; };

// Turns the flagged-pixel count into the blur's indirect dispatch size.
void main() {
  counters[CASCADE_COUNTER_DISPATCH] = (counters[CASCADE_COUNTER_BLUR] + CASCADE_BLUR_GROUP - 1u) / CASCADE_BLUR_GROUP;
  counters[CASCADE_COUNTER_DISPATCH + 1u] = 1u;
  counters[CASCADE_COUNTER_DISPATCH + 2u] = 1u;
}
