# Small helpers so every folder's CMakeLists.txt reads the same.

set(OPENVCU_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wimplicit-fallthrough)

# openvcu_library(<concern> SOURCES ... [DEPS ...] [PUBLIC_DEPS ...])
# builds openvcu_<concern> with alias openvcu::<concern>, public headers in include/.
function(openvcu_library concern)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PUBLIC_DEPS" ${ARGN})
  set(target openvcu_${concern})
  if(ARG_SOURCES)
    add_library(${target} STATIC ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include
                                         PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
    target_compile_options(${target} PRIVATE ${OPENVCU_WARNINGS})
    target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_DEPS})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(${target} INTERFACE ${ARG_PUBLIC_DEPS})
  endif()
  add_library(openvcu::${concern} ALIAS ${target})
endfunction()

# openvcu_unit_test_target(<target>...): executables that `ctest -L unit` runs. The target
# `unit-tests` builds exactly these (and what they depend on): test.sh builds only it under
# ASan, and checks that its build lists as many unit tests as the full Release build.
function(openvcu_unit_test_target)
  set_property(GLOBAL APPEND PROPERTY OPENVCU_UNIT_TEST_TARGETS ${ARGN})
endfunction()

# openvcu_test(<name> SOURCES ... DEPS ... [LABELS ...]): one doctest executable,
# every TEST_CASE registered with ctest.
function(openvcu_test name)
  cmake_parse_arguments(ARG "SERIAL" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES} ${PROJECT_SOURCE_DIR}/tests/doctest_main.cpp)
  target_compile_options(${name} PRIVATE ${OPENVCU_WARNINGS} -Wno-old-style-cast)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(${name} PRIVATE doctest::doctest ${ARG_DEPS})
  target_compile_definitions(${name} PRIVATE
    OPENVCU_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    OPENVCU_TEAM_KIT="${OPENVCU_TEAM_KIT}"
    OPENVCU_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set(labels unit)
  if(ARG_LABELS)
    set(labels ${ARG_LABELS})
  endif()
  if("unit" IN_LIST labels)
    openvcu_unit_test_target(${name})
  endif()
  # SERIAL: timing checks that must not share the 2 cores with other tests (RUN_SERIAL)
  set(serial FALSE)
  if(ARG_SERIAL)
    set(serial TRUE)
  endif()
  # a case that skips itself (tests/skip.hpp) exits with 77: ctest shows it as skipped
  doctest_discover_tests(${name} PROPERTIES LABELS "${labels}" RUN_SERIAL ${serial} SKIP_RETURN_CODE 77)
endfunction()

# What installs without a COMPONENT goes into the Debian package openvcu (the HMI names its
# own, hmi: cmake/OpenvcuPackaging.cmake).
set(CMAKE_INSTALL_DEFAULT_COMPONENT_NAME openvcu)

# openvcu_executable(<installed name> SOURCES ... DEPS ...)
function(openvcu_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_compile_options(${name} PRIVATE ${OPENVCU_WARNINGS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bin)
  install(TARGETS ${name} RUNTIME DESTINATION bin)
endfunction()
