// Files for the simulator's tests: a scratch folder per test process, and a
// file's whole content.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace hyq::sim {

// <temp>/<prefix><pid>, created if missing.
inline std::filesystem::path testTempDir(const std::string& prefix) {
  const auto d = std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
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
