#include "engine/platform/headless.hpp"

#include <cstdlib>

namespace engine::platform {
bool display_available() {
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return (x11 && *x11) || (wayland && *wayland);
}
}  // namespace engine::platform
