#pragma once
// A fresh, empty folder under the system's temporary folder for one test, named by the suite,
// the process and the case (parallel ctest runs do not share one).

#include <unistd.h>

#include <filesystem>
#include <string>

namespace staa::test {

inline std::filesystem::path freshDir(const std::string& suite, const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / (suite + "-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace staa::test
