#include "input.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace walkthrough {

namespace {
struct KeyName {
  const char* name;
  uint32_t bit;
};
constexpr KeyName kKeyNames[] = {{"W", kKeyForward}, {"A", kKeyLeft},   {"S", kKeyBack},  {"D", kKeyRight},
                                 {"Shift", kKeySprint}, {"Space", kKeyJump}, {"Ctrl", kKeyDown}, {"Fly", kKeyFly}};

bool parse_float(const std::string& s, float& out) {
  try {
    size_t used = 0;
    out = std::stof(s, &used);
    return used == s.size() && std::isfinite(out);
  } catch (const std::exception&) {
    return false;
  }
}
}  // namespace

std::string keys_to_string(uint32_t keys) {
  std::string out;
  for (const auto& k : kKeyNames) {
    if (!(keys & k.bit)) continue;
    if (!out.empty()) out += '+';
    out += k.name;
  }
  return out.empty() ? "-" : out;
}

std::vector<InputFrame> load_input_script(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open input script");
  std::vector<InputFrame> frames;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    std::vector<std::string> f;
    for (std::string s; fields >> s;) f.push_back(s);
    if (f.empty()) continue;
    const std::string where = path.string() + ":" + std::to_string(number) + ": ";
    if (f.size() != 4 && f.size() != 5)
      throw std::runtime_error(where + "expected 'DT KEYS MOUSE_DX MOUSE_DY [REPEAT]', got " + std::to_string(f.size()) +
                               " fields");
    InputFrame frame;
    if (!parse_float(f[0], frame.dt) || frame.dt <= 0.0f || frame.dt > 1.0f)
      throw std::runtime_error(where + "DT '" + f[0] + "' must be a number of seconds in (0, 1]");
    if (f[1] != "-") {
      std::istringstream names(f[1]);
      for (std::string name; std::getline(names, name, '+');) {
        uint32_t bit = 0;
        for (const auto& k : kKeyNames)
          if (name == k.name) bit = k.bit;
        if (!bit) throw std::runtime_error(where + "unknown key '" + name + "' (W A S D Shift Space Ctrl Fly)");
        frame.keys |= bit;
      }
    }
    if (!parse_float(f[2], frame.mouse_dx)) throw std::runtime_error(where + "MOUSE_DX '" + f[2] + "' is not a number");
    if (!parse_float(f[3], frame.mouse_dy)) throw std::runtime_error(where + "MOUSE_DY '" + f[3] + "' is not a number");
    float repeat = 1.0f;
    if (f.size() == 5 && (!parse_float(f[4], repeat) || repeat < 1.0f || repeat > 1e6f || repeat != std::floor(repeat)))
      throw std::runtime_error(where + "REPEAT '" + f[4] + "' must be a whole number >= 1");
    frames.insert(frames.end(), size_t(repeat), frame);
  }
  if (frames.empty()) throw std::runtime_error(path.string() + ": input script has no frames");
  return frames;
}

void save_input_script(const std::filesystem::path& path, const std::vector<InputFrame>& frames) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write input script");
  out << "# walkthrough input script: DT KEYS MOUSE_DX MOUSE_DY [REPEAT] (see sample_game/input.hpp)\n";
  for (size_t i = 0; i < frames.size();) {
    size_t j = i + 1;
    while (j < frames.size() && frames[j].dt == frames[i].dt && frames[j].keys == frames[i].keys &&
           frames[j].mouse_dx == frames[i].mouse_dx && frames[j].mouse_dy == frames[i].mouse_dy)
      ++j;
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%.6g %s %.6g %.6g", frames[i].dt, keys_to_string(frames[i].keys).c_str(),
                  frames[i].mouse_dx, frames[i].mouse_dy);
    out << buf;
    if (j - i > 1) out << ' ' << (j - i);
    out << '\n';
    i = j;
  }
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace walkthrough
