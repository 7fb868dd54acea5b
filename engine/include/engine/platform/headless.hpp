#pragma once
#include <string>

namespace engine::platform {
// True when a window system is reachable (X11 DISPLAY or WAYLAND_DISPLAY set).
bool display_available();
}  // namespace engine::platform
