# openvcu_write_isolated_launcher(<output> <binary dir> <source dir> <team kit>): writes the
# launcher ctest puts in front of every case of an isolated test (CROSSCOMPILING_EMULATOR,
# which doctest_discover_tests honours). Listing the cases at build time needs no sandbox;
# every other command runs in run_isolated.sh, with the build and source trees bound back in
# when they live under /tmp, and the team kit (if it exists when the test runs) bound in
# read-only at its own path: its corpus tests then run from a clone under /tmp as well.
#
# Also a script, so a test can write a launcher for another tree layout:
#   cmake -DOUTPUT=FILE -DBINARY_DIR=DIR -DSOURCE_DIR=DIR -DTEAM_KIT=DIR -P isolated_launcher.cmake
set(OPENVCU_RUN_ISOLATED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/run_isolated.sh)

function(openvcu_write_isolated_launcher output binaryDir sourceDir teamKit)
  file(CONFIGURE OUTPUT ${output} CONTENT
"#!/bin/sh
case \" $* \" in *\" --list-test-cases \"*|*\" --list-test-suites \"*) exec \"$@\" ;; esac
if [ -d '${teamKit}' ]; then
  exec '${OPENVCU_RUN_ISOLATED_SCRIPT}' --keep '${binaryDir}' --keep '${sourceDir}' --keep-ro '${teamKit}' -- \"$@\"
fi
exec '${OPENVCU_RUN_ISOLATED_SCRIPT}' --keep '${binaryDir}' --keep '${sourceDir}' -- \"$@\"
")
  file(CHMOD ${output} PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE
       WORLD_READ WORLD_EXECUTE)
endfunction()

if(CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  foreach(var OUTPUT BINARY_DIR SOURCE_DIR TEAM_KIT)
    if(NOT DEFINED ${var})
      message(FATAL_ERROR "isolated_launcher.cmake: -D${var}=... is missing")
    endif()
  endforeach()
  openvcu_write_isolated_launcher(${OUTPUT} ${BINARY_DIR} ${SOURCE_DIR} ${TEAM_KIT})
endif()
