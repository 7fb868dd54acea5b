#pragma once
// A small reader for "--flag value" command lines shared by the engine's executables. Errors are
// std::runtime_error with one line naming the flag.
#include <charconv>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace engine {

class CommandLine {
 public:
  CommandLine(int argc, char** argv) : argc_(argc), argv_(argv) {}

  // Advances to the next argument; false at the end.
  bool next() {
    if (++index_ >= argc_) return false;
    flag_ = argv_[index_];
    return true;
  }
  const std::string& flag() const { return flag_; }

  std::string value() {
    if (index_ + 1 >= argc_) throw std::runtime_error(flag_ + " needs a value");
    return argv_[++index_];
  }

  uint32_t uint_value() {
    const std::string v = value();
    uint32_t out = 0;
    auto r = std::from_chars(v.data(), v.data() + v.size(), out);
    if (r.ec != std::errc() || r.ptr != v.data() + v.size() || v.empty())
      throw std::runtime_error(flag_ + " '" + v + "': expected a non-negative whole number");
    return out;
  }

  // "WxH" with both in 1..16384.
  void size_value(uint32_t& width, uint32_t& height) {
    const std::string v = value();
    const auto x = v.find('x');
    uint32_t w = 0, h = 0;
    bool ok = x != std::string::npos;
    if (ok) {
      auto r1 = std::from_chars(v.data(), v.data() + x, w);
      auto r2 = std::from_chars(v.data() + x + 1, v.data() + v.size(), h);
      ok = r1.ec == std::errc() && r2.ec == std::errc() && r1.ptr == v.data() + x && r2.ptr == v.data() + v.size();
    }
    if (!ok || w == 0 || h == 0 || w > 16384 || h > 16384)
      throw std::runtime_error(flag_ + " '" + v + "': expected WxH, each 1..16384");
    width = w;
    height = h;
  }

 private:
  int argc_;
  char** argv_;
  int index_ = 0;
  std::string flag_;
};

}  // namespace engine
