# The `openvcu-runtime` target: every built artifact ./run.sh and the Debian packages use at
# run time, and nothing else (no tests, benchmarks or fuzz corpus replays), so that the first
# ./run.sh builds what it runs (`cmake --build build --target openvcu-runtime`).
#   the services     vcu-can-rx vcu-can-tx vcu-fsm vcu-gpio vcu-ecu-sim vcu-web vcu-telemetry
#   the tool         vcu (run.sh's check, status, top, signal set, record and init)
#   the HMI          vcu-hmi, when services/hmi found Qt 6 (else that target does not exist)
#   the LCM types    openvcu_lcm_jar, the Java types `vcu spy` hands lcm-spy (when a JDK is found)
# Included from the top CMakeLists.txt after shared/, services/ and tools/. A target that a
# configuration leaves out (OPENVCU_BUILD_HMI=OFF, no Qt, no JDK) is skipped; a missing
# service or vcu is skipped too, with a warning (run.sh would then say what is not built).
set(OPENVCU_RUNTIME_REQUIRED vcu-can-rx vcu-can-tx vcu-fsm vcu-gpio vcu-ecu-sim vcu-web vcu-telemetry vcu)
set(OPENVCU_RUNTIME_OPTIONAL vcu-hmi openvcu_lcm_jar)

set(runtimeDeps "")
foreach(target IN LISTS OPENVCU_RUNTIME_REQUIRED)
  if(TARGET ${target})
    list(APPEND runtimeDeps ${target})
  else()
    message(WARNING "openvcu-runtime: no target ${target} (is cmake/OpenvcuRuntimeTarget.cmake "
                    "included before its folder is added?): openvcu-runtime goes without it")
  endif()
endforeach()
foreach(target IN LISTS OPENVCU_RUNTIME_OPTIONAL)
  if(TARGET ${target})
    list(APPEND runtimeDeps ${target})
  endif()
endforeach()

add_custom_target(openvcu-runtime)
if(runtimeDeps)
  add_dependencies(openvcu-runtime ${runtimeDeps})
endif()
# the list, for scripts/package.sh and the report of what a configuration builds
set_property(GLOBAL PROPERTY OPENVCU_RUNTIME_TARGETS ${runtimeDeps})
message(STATUS "openvcu-runtime: ${runtimeDeps}")
