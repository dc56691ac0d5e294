// The headers nearly every test file includes, precompiled once per build (tests/CMakeLists.txt,
// STAA_TEST_PCH): parsing GoogleTest, nlohmann/json and Eigen was most of a test file's
// compile time. Only third-party and standard headers: a project header here would make every
// test rebuild when it changes.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>
