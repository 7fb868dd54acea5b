#pragma once
// One frame of player input (keys held, mouse movement) and the text scripts that record and replay
// it. Script format, one frame per line ('#' starts a comment):
//
//   DT KEYS MOUSE_DX MOUSE_DY [REPEAT]
//
//   DT        seconds the frame simulates (e.g. 0.05)
//   KEYS      '-' for none, or key names joined by '+': W A S D Shift Space Ctrl Fly
//             (Fly toggles flying on the frame it appears after a frame without it)
//   MOUSE_DX  horizontal mouse movement in pixels (positive turns right)
//   MOUSE_DY  vertical mouse movement in pixels (positive looks down)
//   REPEAT    optional: the line stands for this many identical frames (default 1)
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace walkthrough {

enum InputKey : uint32_t {
  kKeyForward = 1u << 0,  // W
  kKeyLeft = 1u << 1,     // A
  kKeyBack = 1u << 2,     // S
  kKeyRight = 1u << 3,    // D
  kKeySprint = 1u << 4,   // Shift
  kKeyJump = 1u << 5,     // Space (up while flying)
  kKeyDown = 1u << 6,     // Ctrl (down while flying)
  kKeyFly = 1u << 7,      // F: toggles flying when pressed
};

struct InputFrame {
  float dt = 1.0f / 60.0f;
  uint32_t keys = 0;
  float mouse_dx = 0.0f;
  float mouse_dy = 0.0f;
};

std::string keys_to_string(uint32_t keys);

// Reads a script; throws std::runtime_error naming the file, line and problem.
std::vector<InputFrame> load_input_script(const std::filesystem::path& path);
// Writes frames, merging identical consecutive frames into one line with a repeat count.
void save_input_script(const std::filesystem::path& path, const std::vector<InputFrame>& frames);

}  // namespace walkthrough
