# ROS 1 (Debian 12's roscpp 1.15 and its message packages), found through pkg-config.
# Defines STAA_HAVE_ROS1 (ON/OFF), the interface target staa::ros1 (the libraries and their
# include folders) and staa_ros1_target(TARGET), which links a target with staa::ros1 and
# compiles it as C++17: the ROS 1 message headers do not compile as C++20 (they use
# std::allocator<void>::rebind). A translation unit that includes a ROS header must
# therefore not include the project's C++20 headers; plain C++ helpers may stay C++20.
# Included once, by the top-level CMakeLists.txt (its variables are seen by every folder).
include_guard(GLOBAL)

find_package(PkgConfig REQUIRED)
set(STAA_ROS1_MODULES roscpp rosgraph_msgs std_msgs geometry_msgs nav_msgs sensor_msgs
  tf2_ros tf2_msgs actionlib actionlib_msgs move_base_msgs visualization_msgs diagnostic_msgs)
pkg_check_modules(STAA_ROS1 QUIET IMPORTED_TARGET GLOBAL ${STAA_ROS1_MODULES})

if(STAA_ROS1_FOUND)
  set(STAA_HAVE_ROS1 ON)
  add_library(staa::ros1 INTERFACE IMPORTED GLOBAL)
  target_link_libraries(staa::ros1 INTERFACE PkgConfig::STAA_ROS1)
  message(STATUS "ROS 1 found (roscpp ${STAA_ROS1_roscpp_VERSION}): the ROS tests are built")
else()
  set(STAA_HAVE_ROS1 OFF)
  # Which of the modules pkg-config does not know, so the message names what to install.
  set(missing "")
  foreach(m IN LISTS STAA_ROS1_MODULES)
    execute_process(COMMAND ${PKG_CONFIG_EXECUTABLE} --exists ${m} RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
      list(APPEND missing ${m})
    endif()
  endforeach()
  list(JOIN missing " " missing)
  message(STATUS "ROS 1 not found (pkg-config lacks: ${missing}): the ROS tests and the ROS "
                 "backend are skipped (toolchain/install-deps.sh installs the packages)")
endif()

function(staa_ros1_target target)
  target_link_libraries(${target} PRIVATE staa::ros1)
  # Never a unity build: our namespace staa::staad::ros would hide ROS's ::ros in the files after.
  set_target_properties(${target} PROPERTIES CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON CXX_EXTENSIONS OFF
                                             UNITY_BUILD OFF)
endfunction()
