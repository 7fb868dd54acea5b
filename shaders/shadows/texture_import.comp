#version 460
#extension GL_GOOGLE_include_directive : require
#include "host.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push { TextureImportPush push; };
layout(set = 0, binding = TEXTURE_IMPORT_BINDING_SOURCE) uniform sampler2D source;
layout(std430, set = 0, binding = TEXTURE_IMPORT_BINDING_WORDS) writeonly buffer Words { uint words[]; };

// A host alpha texture's level 0 into the material-texture words (RGBA8, r in the low byte), so every
// alpha test reads the same texel as the engine's own textures do.
void main() {
  uvec2 texel = gl_GlobalInvocationID.xy;
  if (texel.x >= push.width || texel.y >= push.height) return;
  vec4 c = texelFetch(source, ivec2(texel), 0);
  if (push.alpha_from_red != 0u) c = vec4(1.0, 1.0, 1.0, c.r);
  words[push.first_word + texel.y * push.width + texel.x] = packUnorm4x8(c);
}
