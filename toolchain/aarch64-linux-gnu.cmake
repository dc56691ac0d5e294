# Cross-compiling staa for aarch64 (a robot PC or a Jetson) from a Debian 12 x86-64 host,
# against an arm64 sysroot of its own (no arm64 packages on the host: Debian 12's
# libyaml-cpp-dev is not multi-arch, and its arm64 package would remove the host's):
#
#   bash toolchain/install-deps.sh --aarch64   # cross g++, qemu-user, mmdebstrap, the sysroot
#   cmake --workflow --preset aarch64          # configure, cross-build, run the tests under qemu
#
# or, step by step: cmake --preset aarch64 && cmake --build --preset aarch64 &&
# ctest --preset aarch64. The sysroot is $STAA_AARCH64_SYSROOT (for install-deps.sh and here
# alike) or /opt/staa-sysroot-arm64. The programs in build/aarch64 run on the robot with the
# same Debian 12 libraries installed, or here: qemu-aarch64 -L <sysroot> build/aarch64/...
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(STAA_CROSS_TRIPLE aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${STAA_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${STAA_CROSS_TRIPLE}-g++)

if(DEFINED ENV{STAA_AARCH64_SYSROOT} AND NOT "$ENV{STAA_AARCH64_SYSROOT}" STREQUAL "")
  set(STAA_AARCH64_SYSROOT "$ENV{STAA_AARCH64_SYSROOT}")
elseif(NOT STAA_AARCH64_SYSROOT)
  set(STAA_AARCH64_SYSROOT /opt/staa-sysroot-arm64)
endif()
# install-deps.sh writes this file last, when the sysroot is complete.
if(NOT EXISTS "${STAA_AARCH64_SYSROOT}/.staa-sysroot")
  message(FATAL_ERROR "No arm64 sysroot in ${STAA_AARCH64_SYSROOT}: run "
    "`bash toolchain/install-deps.sh --aarch64` (as root) first")
endif()
# try_compile projects read this file again: give them the same sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES STAA_AARCH64_SYSROOT)

# The cross compiler's own libc and libstdc++ (/usr/aarch64-linux-gnu) come first; the
# project's libraries, their headers, CMake and pkg-config files only from the sysroot.
set(CMAKE_SYSROOT "${STAA_AARCH64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (the host's program) must read the sysroot's arm64 .pc files, and only those,
# and prefix the paths they give with the sysroot.
set(ENV{PKG_CONFIG_PATH} "")
set(ENV{PKG_CONFIG_LIBDIR}
  "${STAA_AARCH64_SYSROOT}/usr/lib/${STAA_CROSS_TRIPLE}/pkgconfig:${STAA_AARCH64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${STAA_AARCH64_SYSROOT}")

# ctest and gtest_discover_tests run the arm64 test programs under qemu-user; -L makes its
# dynamic loader and the arm64 shared libraries (yaml-cpp, ccd, polyclipping, libstdc++)
# come from the sysroot.
find_program(STAA_QEMU_AARCH64 qemu-aarch64 REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${STAA_QEMU_AARCH64};-L;${STAA_AARCH64_SYSROOT}")
