#pragma once
// The whole of a file as a string (empty when it cannot be read): what tests compare output
// files and logs with.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace staa::test {

inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace staa::test
