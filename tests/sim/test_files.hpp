// Files for the simulator's tests: a scratch folder per test process, and a
// file's whole content.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <system_error>

namespace hyq::sim {

// <temp>/<prefix><pid>, created if missing, and removed with what it holds
// when the test process exits normally.
inline std::filesystem::path testTempDir(const std::string& prefix) {
  struct Scratch {
    std::set<std::filesystem::path> dirs;
    ~Scratch() {
      for (const auto& d : dirs) {
        std::error_code ignored;  // a folder that cannot be removed is left behind, not an error
        std::filesystem::remove_all(d, ignored);
      }
    }
  };
  static Scratch scratch;
  const auto d = std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  scratch.dirs.insert(d);
  return d;
}

// The file's bytes ("" if it cannot be read).
inline std::string readFile(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace hyq::sim
