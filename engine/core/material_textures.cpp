#include "engine/core/material_textures.hpp"

#include <shared/material.h>

namespace engine {

MaterialTextureTable::MaterialTextureTable(Registry& registry) {
  std::vector<const Texture*> textures;
  registry.each<Material>([&](Entity, Material& m) {
    const Texture* t = m.base_color_texture.get();
    if (!t || t->width == 0 || t->height == 0 || t->rgba.size() != size_t(t->width) * t->height * 4) return;
    if (index_.emplace(t, uint32_t(textures.size())).second) textures.push_back(t);
  });
  words_.assign(1 + textures.size() * gpu_shared::kTextureHeaderWords, 0u);
  words_[0] = uint32_t(textures.size());
  for (size_t i = 0; i < textures.size(); ++i) {
    const Texture& t = *textures[i];
    uint32_t* header = &words_[1 + i * gpu_shared::kTextureHeaderWords];
    header[0] = uint32_t(words_.size());
    header[1] = t.width;
    header[2] = t.height;
    header[3] = uint32_t(t.wrap_s) | (uint32_t(t.wrap_t) << 8);
    for (size_t p = 0; p < size_t(t.width) * t.height; ++p)
      words_.push_back(uint32_t(t.rgba[4 * p]) | (uint32_t(t.rgba[4 * p + 1]) << 8) |
                       (uint32_t(t.rgba[4 * p + 2]) << 16) | (uint32_t(t.rgba[4 * p + 3]) << 24));
  }
}

uint32_t MaterialTextureTable::index_of(const Material& m) const {
  auto it = index_.find(m.base_color_texture.get());
  return it == index_.end() ? gpu_shared::kNoTexture : it->second;
}

uint32_t MaterialTextureTable::texel(uint32_t texture, glm::vec2 uv) const {
  if (texture == gpu_shared::kNoTexture || texture >= texture_count()) return 0xffffffffu;
  const uint32_t* h = &words_[1 + texture * gpu_shared::kTextureHeaderWords];
  return words_[gpu_shared::texel_word(glm::uvec4(h[0], h[1], h[2], h[3]), uv)];
}

bool MaterialTextureTable::alpha_kept(uint32_t texture, uint32_t threshold, glm::vec2 uv) const {
  if (threshold == 0) return true;
  return gpu_shared::alpha_byte_kept(texel(texture, uv), threshold);
}

}  // namespace engine
