# Writes OUT (a header defining STAA_GIT_REVISION, `git describe --always --dirty` of SOURCE)
# when the revision changed, so that a recording names the build it came from without
# recompiling anything else. Run at every build: cmake -DSOURCE=... -DOUT=... -P this file.
execute_process(COMMAND git describe --always --dirty --abbrev=10
                WORKING_DIRECTORY ${SOURCE}
                OUTPUT_VARIABLE revision OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
set(text "#pragma once\n#define STAA_GIT_REVISION \"${revision}\"\n")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT "${old}" STREQUAL "${text}")
  file(WRITE ${OUT} "${text}")
endif()
