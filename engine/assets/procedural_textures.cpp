#include "engine/assets/procedural_textures.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/constants.hpp>

namespace engine::procedural {

namespace {
void put(Texture& t, uint32_t x, uint32_t y, glm::vec3 rgb, uint8_t alpha) {
  uint8_t* p = &t.rgba[(size_t(y) * t.width + x) * 4];
  for (int c = 0; c < 3; ++c) p[c] = uint8_t(std::clamp(rgb[c], 0.0f, 1.0f) * 255.0f + 0.5f);
  p[3] = alpha;
}
}  // namespace

std::shared_ptr<const Texture> make_leaf_spray_texture(uint32_t size, int leaves) {
  auto t = std::make_shared<Texture>();
  t->name = "generated leaf spray";
  t->width = t->height = size;
  t->rgba.assign(size_t(size) * size * 4, 0);
  t->wrap_s = t->wrap_t = TextureWrap::ClampToEdge;
  const int n = std::max(1, leaves);
  for (uint32_t y = 0; y < size; ++y) {
    for (uint32_t x = 0; x < size; ++x) {
      // Texture coordinates with v = 0 at the top row; the stems meet at the bottom centre.
      const glm::vec2 p{(float(x) + 0.5f) / float(size), (float(y) + 0.5f) / float(size)};
      const glm::vec2 from_base = glm::vec2(p.x - 0.5f, 0.98f - p.y);
      bool inside = false;
      float along_best = 0.0f, across_best = 1.0f;
      for (int i = 0; i < n; ++i) {
        // Leaves fan over +-70 degrees around straight up, alternating lengths.
        const float angle = glm::radians(n == 1 ? 0.0f : -70.0f + 140.0f * float(i) / float(n - 1));
        const glm::vec2 axis{std::sin(angle), std::cos(angle)};
        const float length = (i % 2 == 0 ? 0.9f : 0.72f) * (1.0f - 0.15f * std::abs(std::sin(angle)));
        const float stem = 0.12f;  // bare stalk before the blade
        const float along = glm::dot(from_base, axis);
        const float across = std::abs(from_base.x * axis.y - from_base.y * axis.x);
        const float s = (along - stem) / (length - stem);  // 0..1 along the blade
        if (along > 0.0f && along < stem && across < 0.008f) inside = true;
        if (s <= 0.0f || s >= 1.0f) continue;
        // Blade half-width: widest a third of the way up, pointed at the tip.
        const float half_width = 0.11f * std::pow(std::sin(glm::pi<float>() * std::pow(s, 0.75f)), 0.9f);
        if (across < half_width) {
          inside = true;
          along_best = s;
          across_best = across / half_width;
        }
      }
      if (!inside) continue;
      const glm::vec3 dark{0.10f, 0.30f, 0.07f}, light{0.30f, 0.55f, 0.16f};
      glm::vec3 rgb = glm::mix(dark, light, 0.4f + 0.6f * along_best * (1.0f - 0.5f * across_best));
      if (across_best < 0.08f) rgb = glm::mix(rgb, glm::vec3(0.55f, 0.7f, 0.3f), 0.6f);  // midrib
      put(*t, x, y, rgb, 255);
    }
  }
  return t;
}

std::shared_ptr<const Texture> make_grate_texture(uint32_t size, int bars, float bar_fraction) {
  auto t = std::make_shared<Texture>();
  t->name = "generated grate";
  t->width = t->height = size;
  t->rgba.assign(size_t(size) * size * 4, 0);
  const float cells = float(std::max(1, bars));
  for (uint32_t y = 0; y < size; ++y) {
    for (uint32_t x = 0; x < size; ++x) {
      const float cx = std::fmod((float(x) + 0.5f) / float(size) * cells, 1.0f);
      const float cy = std::fmod((float(y) + 0.5f) / float(size) * cells, 1.0f);
      const bool bar = cx < bar_fraction || cy < bar_fraction;
      if (bar) put(*t, x, y, glm::vec3(0.22f, 0.22f, 0.24f) * (cx < bar_fraction ? 1.0f : 0.85f), 255);
    }
  }
  return t;
}

}  // namespace engine::procedural
