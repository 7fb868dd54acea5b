#pragma once
// Textures the project draws in code (no image files): alpha masks for cut-out geometry.
#include <memory>

#include "engine/core/components.hpp"

namespace engine::procedural {

// A spray of `leaves` pointed leaves fanning up from the bottom centre of a square `size`² image:
// alpha 255 inside a leaf, 0 between leaves (the holes light passes through); green shades with a
// lighter midrib. Wraps clamp to the edge.
std::shared_ptr<const Texture> make_leaf_spray_texture(uint32_t size, int leaves);

// A square grate of `bars` x `bars` bars over a `size`² image: alpha 255 on the bars (each
// `bar_fraction` of its cell wide), 0 in the openings; dark metal colour. Repeats.
std::shared_ptr<const Texture> make_grate_texture(uint32_t size, int bars, float bar_fraction);

}  // namespace engine::procedural
