// Values from a uniform buffer (or push constants) that decide an `if` or bound a loop on their own,
// for a CPU device. lavapipe (Mesa 22.x) folds such values into the shader at every dispatch and, as
// it keeps none of the variants, compiles the shader anew each time: 50-400 ms a dispatch with its
// shader cache cold, 1-2 ms warm (BENCHMARKS.md, "Shaders compiled at every dispatch on lavapipe").
// Passed through a subgroup broadcast the value is the same but no longer a plain uniform load, so
// the pipeline is compiled once. Define UNIFORM_BRANCH_CPU (a bool, true on a CPU device) before
// including; on a GPU the value passes through untouched, as it does everywhere where
// SHADOWS_WITHOUT_SUBGROUP_OPS is defined (a shader's variant for a device without subgroup ballot,
// which lavapipe has).
#ifndef UNIFORM_BRANCH_GLSL
#define UNIFORM_BRANCH_GLSL
#ifdef SHADOWS_WITHOUT_SUBGROUP_OPS
uint uniform_branch(uint value) { return value; }
float uniform_branch(float value) { return value; }
#else
#extension GL_KHR_shader_subgroup_ballot : require
uint uniform_branch(uint value) { return UNIFORM_BRANCH_CPU ? subgroupBroadcastFirst(value) : value; }
float uniform_branch(float value) { return UNIFORM_BRANCH_CPU ? subgroupBroadcastFirst(value) : value; }
#endif
#endif
