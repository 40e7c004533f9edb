# Cross-compiles openvcu for arm64 (aarch64, e.g. a Raspberry Pi 4/5 on Debian 12) on an
# amd64 Debian 12 machine with Debian's cross toolchain and multiarch libraries:
#   crossbuild-essential-arm64 (aarch64-linux-gnu-gcc/g++), the :arm64 -dev packages in
#   /usr/lib/aarch64-linux-gnu and /usr/include, qemu-user-static to run the test binaries.
# scripts/cross-arm64.sh installs all of that and uses this file:
#   cmake -S . -B build-arm64 -G Ninja -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake
#
# OPENVCU_ARM64_EXTRA_ROOT (optional, a folder): arm64 packages unpacked outside dpkg
# (scripts/cross-arm64.sh puts liblcm there: Debian's liblcm1/liblcm-dev are not
# Multi-Arch: same and cannot be installed beside the amd64 ones). Searched after the system.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_STRIP aarch64-linux-gnu-strip CACHE FILEPATH "arm64 strip (cpack, install/strip)")
set(CMAKE_OBJCOPY aarch64-linux-gnu-objcopy CACHE FILEPATH "")
set(CMAKE_OBJDUMP aarch64-linux-gnu-objdump CACHE FILEPATH "")

# The variables a toolchain file sets must reach try_compile projects too.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES OPENVCU_ARM64_EXTRA_ROOT)

# Multiarch: the arm64 libraries live in the host's own tree (/usr/lib/aarch64-linux-gnu,
# found through CMAKE_LIBRARY_ARCHITECTURE), so the root path is / plus the extra root.
# Programs (lcm-gen, moc, rcc, qmlcachegen, java) are host programs: never re-rooted.
set(CMAKE_FIND_ROOT_PATH / ${OPENVCU_ARM64_EXTRA_ROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config: only the arm64 .pc files (plus the arch-independent /usr/share/pkgconfig).
set(_openvcu_pc_dirs /usr/lib/aarch64-linux-gnu/pkgconfig /usr/share/pkgconfig)
if(OPENVCU_ARM64_EXTRA_ROOT)
  # (scripts/cross-arm64.sh rewrites their prefix= to the extra root)
  list(PREPEND _openvcu_pc_dirs ${OPENVCU_ARM64_EXTRA_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig)
endif()
string(REPLACE ";" ":" _openvcu_pc_path "${_openvcu_pc_dirs}")
set(ENV{PKG_CONFIG_LIBDIR} "${_openvcu_pc_path}")
set(ENV{PKG_CONFIG_PATH} "")

# Qt 6: Debian's arm64 Qt packages use the amd64 host tools of qt6-base-dev-tools and
# qt6-declarative-dev-tools (moc, rcc, uic, qmlcachegen, qmltyperegistrar in
# /usr/lib/qt6/libexec), whose CMake packages (Qt6CoreTools, Qt6QmlTools...) come from the
# amd64 -dev packages in /usr/lib/x86_64-linux-gnu/cmake.
set(QT_HOST_PATH /usr CACHE PATH "Qt host tools prefix (amd64)")
set(QT_HOST_PATH_CMAKE_DIR /usr/lib/x86_64-linux-gnu/cmake CACHE PATH "Qt host tools' CMake packages")

# Test binaries (doctest_discover_tests at build time, ctest) run under qemu-user. The
# arm64 dynamic loader and libc come from libc6:arm64 in the host's own tree; -L points
# qemu at / for the interpreter path /lib/ld-linux-aarch64.so.1. Libraries of the extra
# root are found through the build tree's RPATH (CMake adds it; install drops it). Programs
# a test starts itself (vcu, the services) run through binfmt_misc (qemu-user-static).
find_program(OPENVCU_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(OPENVCU_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${OPENVCU_QEMU_AARCH64};-L;/ CACHE STRING "runs arm64 programs on this machine" FORCE)
endif()
