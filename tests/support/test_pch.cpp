// The translation unit that builds tests/support/test_pch.hpp's precompiled header, which the
// test executables reuse (tests/CMakeLists.txt).
