#version 460
#extension GL_GOOGLE_include_directive : require
#define LOCAL_LIGHTS
#include "lighting.glsl"
