#pragma once
// Locates the project's shared/ folder (real ROS maps and other inputs that are never copied
// into the repository). STAA_SHARED_DIR in the environment overrides the configured path.

#include <cstdlib>
#include <filesystem>
#include <string>

namespace staa::test {

inline std::filesystem::path sharedDir() {
  if (const char* env = std::getenv("STAA_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return STAA_SHARED_DIR;
}

inline std::filesystem::path sourceDir() { return STAA_SOURCE_DIR; }

}  // namespace staa::test

// Skips the current test, with the reason, when a shared input is absent.
#define STAA_REQUIRE_SHARED_FILE(path)                                                       \
  do {                                                                                       \
    if (!std::filesystem::exists(path)) {                                                    \
      GTEST_SKIP() << "shared input " << (path).string()                                     \
                   << " not found (run from a checkout with ../shared beside it, or set "    \
                      "STAA_SHARED_DIR)";                                                    \
    }                                                                                        \
  } while (0)
