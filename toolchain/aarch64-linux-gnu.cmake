# Cross-compiling staa for aarch64 (a robot PC or a Jetson) from a Debian 12 x86_64 host.
#
#   dpkg --add-architecture arm64 && apt-get update
#   apt-get install g++-aarch64-linux-gnu libeigen3-dev libccd-dev:arm64 libpolyclipping-dev:arm64 \
#       libyaml-cpp-dev:arm64 libcli11-dev nlohmann-json3-dev
#   cmake --preset aarch64 && cmake --build --preset aarch64
#
# Header-only dependencies (Eigen, CLI11, nlohmann-json) come from the host; libraries are
# found in the arm64 multiarch paths.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(STAA_CROSS_TRIPLE aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${STAA_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${STAA_CROSS_TRIPLE}-g++)

# Look for programs on the host, libraries and headers in the target's multiarch folders.
set(CMAKE_FIND_ROOT_PATH /usr/${STAA_CROSS_TRIPLE} /usr/lib/${STAA_CROSS_TRIPLE})
set(CMAKE_LIBRARY_ARCHITECTURE ${STAA_CROSS_TRIPLE})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)

# pkg-config must report the arm64 .pc files, not the host's.
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${STAA_CROSS_TRIPLE}/pkgconfig:/usr/share/pkgconfig)
set(ENV{PKG_CONFIG_SYSROOT_DIR} /)
