# cmake/OpenvcuPackaging.cmake: the install layout beyond the per-target rules, and CPack's
# Debian packages `openvcu` and `openvcu-hmi` (docs/design/packaging.md).
#
# Included from the top CMakeLists.txt after the services and tools, so the targets exist.
# The executables install themselves (openvcu_executable: bin/, component openvcu, the
# default component set in OpenvcuHelpers.cmake; vcu-hmi: component hmi), vcu-web's pages
# too (services/web). Here: the configuration, the examples, the units, the udev rule, the
# supervisord profile, the Debian documents, and CPack.
#
# The packages are made from this build tree by scripts/package.sh:
#   cmake --build BUILD --target openvcu-packaging-files && cd BUILD && cpack -G DEB
# (packaging prefix /usr; files under /etc and /lib have absolute destinations).

set(OPENVCU_PACKAGING_DIR ${PROJECT_SOURCE_DIR}/packaging)
set(OPENVCU_PACKAGING_OUT ${PROJECT_BINARY_DIR}/packaging)
set(OPENVCU_DEB_REVISION 1)
set(OPENVCU_DEB_VERSION ${PROJECT_VERSION}-${OPENVCU_DEB_REVISION})

# --- Debian architecture of this build tree -------------------------------------------------
# Native builds ask dpkg; a cross build (cmake/toolchains/*.cmake) maps its processor.
if(NOT CMAKE_CROSSCOMPILING)
  execute_process(COMMAND dpkg --print-architecture OUTPUT_VARIABLE OPENVCU_DEB_ARCH
                  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE dpkgResult)
endif()
if(CMAKE_CROSSCOMPILING OR NOT dpkgResult EQUAL 0 OR NOT OPENVCU_DEB_ARCH)
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64|ARM64)$")
    set(OPENVCU_DEB_ARCH arm64)
  elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
    set(OPENVCU_DEB_ARCH amd64)
  elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^armv7")
    set(OPENVCU_DEB_ARCH armhf)
  else()
    set(OPENVCU_DEB_ARCH unknown)
    message(STATUS "openvcu packaging: no Debian architecture for processor '${CMAKE_SYSTEM_PROCESSOR}'")
  endif()
endif()

# --- generated files: /etc/openvcu, conffiles, the Debian changelog ------------------------
# /etc/openvcu = config/hhea changed for an installed VCU (packaging/make-etc-config.py says
# what changes); conffiles lists every file of it; changelog.Debian.gz is compressed as
# Debian policy asks (gzip -9n: no name, no time stamp, so the same input gives the same file).
set(etcOut ${OPENVCU_PACKAGING_OUT}/etc)
file(GLOB hheaFiles CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/hhea/*)
add_custom_command(
  OUTPUT ${etcOut}/vehicle.json ${OPENVCU_PACKAGING_OUT}/conffiles
         ${OPENVCU_PACKAGING_OUT}/changelog.Debian.gz
  COMMAND ${CMAKE_COMMAND} -E rm -rf ${etcOut}
  COMMAND /usr/bin/python3 ${OPENVCU_PACKAGING_DIR}/make-etc-config.py
          ${PROJECT_SOURCE_DIR}/config/hhea ${etcOut}
  COMMAND ${CMAKE_COMMAND} -E copy ${PROJECT_SOURCE_DIR}/config/systemd/openvcu.env ${etcOut}/openvcu.env
  COMMAND ${CMAKE_COMMAND} -DETC_DIR=${etcOut} -DOUT=${OPENVCU_PACKAGING_OUT}/conffiles
          -P ${PROJECT_SOURCE_DIR}/cmake/OpenvcuConffiles.cmake
  COMMAND sh -c "gzip -9nc '${OPENVCU_PACKAGING_DIR}/changelog.Debian' > '${OPENVCU_PACKAGING_OUT}/changelog.Debian.gz'"
  DEPENDS ${hheaFiles} ${OPENVCU_PACKAGING_DIR}/make-etc-config.py
          ${PROJECT_SOURCE_DIR}/config/systemd/openvcu.env ${OPENVCU_PACKAGING_DIR}/changelog.Debian
          ${PROJECT_SOURCE_DIR}/cmake/OpenvcuConffiles.cmake
  COMMENT "openvcu packaging: /etc/openvcu from config/hhea, conffiles, changelog.Debian.gz"
  VERBATIM)
add_custom_target(openvcu-packaging-files ALL
  DEPENDS ${etcOut}/vehicle.json ${OPENVCU_PACKAGING_OUT}/conffiles ${OPENVCU_PACKAGING_OUT}/changelog.Debian.gz)

# --- package openvcu -----------------------------------------------------------------------
# Rules with absolute destinations (/etc, /lib) and the Debian documents are EXCLUDE_FROM_ALL:
# only a component install (CPack's) takes them, so a plain `cmake --install BUILD --prefix
# /usr/local` installs programs and /usr/local/share/openvcu and never replaces a configured
# /etc/openvcu or the system's units.
set(comp COMPONENT openvcu)
install(DIRECTORY ${etcOut}/ DESTINATION /etc/openvcu ${comp} EXCLUDE_FROM_ALL)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/hhea/ DESTINATION share/openvcu/vehicles/hhea ${comp})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/tractor/ DESTINATION share/openvcu/vehicles/tractor ${comp})
install(PROGRAMS ${PROJECT_SOURCE_DIR}/config/iceoryx/iox-roudi.sh DESTINATION share/openvcu/iceoryx ${comp})
install(FILES ${PROJECT_SOURCE_DIR}/config/iceoryx/roudi.toml DESTINATION share/openvcu/iceoryx ${comp})
install(FILES ${OPENVCU_PACKAGING_DIR}/supervisor/openvcu.conf DESTINATION share/openvcu/supervisor ${comp})
# vcu-telemetry's example broker setup (ACL, mosquitto.conf, how to make the password file)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/services/telemetry/examples/
        DESTINATION share/doc/openvcu/examples/telemetry ${comp} EXCLUDE_FROM_ALL)
set(openvcuUnits openvcu.target openvcu-roudi.service openvcu-can-rx.service openvcu-can-tx.service
    openvcu-fsm.service openvcu-gpio.service openvcu-web.service openvcu-ecu-sim.service
    openvcu-telemetry.service openvcu-watchdog.service openvcu-bench.target)
list(TRANSFORM openvcuUnits PREPEND ${PROJECT_SOURCE_DIR}/config/systemd/ OUTPUT_VARIABLE unitFiles)
install(FILES ${unitFiles} DESTINATION /lib/systemd/system ${comp} EXCLUDE_FROM_ALL)
install(FILES ${OPENVCU_PACKAGING_DIR}/60-openvcu.rules DESTINATION /lib/udev/rules.d ${comp} EXCLUDE_FROM_ALL)
install(FILES ${OPENVCU_PACKAGING_DIR}/copyright ${OPENVCU_PACKAGING_OUT}/changelog.Debian.gz
        DESTINATION share/doc/openvcu ${comp} EXCLUDE_FROM_ALL)

# --- package openvcu-hmi (when vcu-hmi is built: Qt 6 found) --------------------------------
set(OPENVCU_PACKAGE_COMPONENTS openvcu)
if(TARGET vcu-hmi)
  list(APPEND OPENVCU_PACKAGE_COMPONENTS hmi)
  install(FILES ${PROJECT_SOURCE_DIR}/config/systemd/openvcu-hmi.service DESTINATION /lib/systemd/system
          COMPONENT hmi EXCLUDE_FROM_ALL)
  install(FILES ${OPENVCU_PACKAGING_DIR}/copyright ${OPENVCU_PACKAGING_OUT}/changelog.Debian.gz
          DESTINATION share/doc/openvcu-hmi COMPONENT hmi EXCLUDE_FROM_ALL)
endif()

# --- CPack: Debian packages ----------------------------------------------------------------
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME openvcu)
set(CPACK_PACKAGE_VENDOR "openvcu")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
# Each package's Description (below) starts with its own synopsis line. CPack 3.25 would put
# one global summary (the project's DESCRIPTION) in front of both unless the summary is its
# default text, which it leaves out.
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${CMAKE_PROJECT_NAME} built using CMake")
set(CPACK_PACKAGE_CONTACT "openvcu maintainers <maintainers@users.noreply.h-seed-dd51a4e0.example>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/cpack)
set(CPACK_COMPONENTS_ALL ${OPENVCU_PACKAGE_COMPONENTS})
set(CPACK_DEB_COMPONENT_INSTALL ON)
# CMAKE_STRIP is the toolchain's strip (aarch64-linux-gnu-strip in the cross build)
set(CPACK_STRIP_FILES ON)
# /etc, /lib/systemd, /lib/udev are absolute destinations on purpose
set(CPACK_WARN_ON_ABSOLUTE_INSTALL_DESTINATION OFF)

set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${OPENVCU_DEB_ARCH})
set(CPACK_DEBIAN_PACKAGE_RELEASE ${OPENVCU_DEB_REVISION})
# <name>_<version>-<revision>_<arch>.deb
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER ${CPACK_PACKAGE_CONTACT})
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# dpkg-shlibdeps names the shared libraries' packages (libiceoryx*, liblcm, libgpiod, Qt...)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# maintainer scripts 0755, conffiles 0644 whatever the source files' modes
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)

set(CPACK_DEBIAN_OPENVCU_PACKAGE_NAME openvcu)
set(CPACK_DEBIAN_OPENVCU_PACKAGE_SECTION misc)
# iox-roudi (package iceoryx) is run, not linked; adduser makes the system user in postinst
set(CPACK_DEBIAN_OPENVCU_PACKAGE_DEPENDS "iceoryx, adduser")
# The arm64 cross build (scripts/cross-arm64.sh) links liblcm1:arm64 unpacked outside dpkg
# (liblcm1 is not Multi-Arch: same, so it cannot sit beside the amd64 one): dpkg-shlibdeps
# finds the library there but no package owns it, so its dependency is named here, as
# liblcm1's own shlibs file ("liblcm 1 liblcm1") names it.
if(OPENVCU_ARM64_EXTRA_ROOT)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${OPENVCU_ARM64_EXTRA_ROOT}/usr/lib/aarch64-linux-gnu)
  string(APPEND CPACK_DEBIAN_OPENVCU_PACKAGE_DEPENDS ", liblcm1")
endif()
set(CPACK_DEBIAN_OPENVCU_PACKAGE_RECOMMENDS "can-utils")
set(CPACK_DEBIAN_OPENVCU_PACKAGE_SUGGESTS "supervisor")
set(CPACK_DEBIAN_OPENVCU_DESCRIPTION "open vehicle-control-unit stack
openvcu runs a vehicle control unit on Linux: CAN receive and DBC decode
into a shared signal table, cyclic transmit with J1939-76 pairs, a JSON
state machine, relay outputs over libgpiod, a web interface, the vcu
command line tool and a simulated vehicle for benches.

The services run as the system user openvcu under systemd (openvcu.target,
enabled but not started at install). /etc/openvcu holds the HHEA example
configuration on SocketCAN can0.")
set(CPACK_DEBIAN_OPENVCU_PACKAGE_CONTROL_EXTRA
    ${OPENVCU_PACKAGING_DIR}/openvcu/postinst ${OPENVCU_PACKAGING_DIR}/openvcu/prerm
    ${OPENVCU_PACKAGING_DIR}/openvcu/postrm ${OPENVCU_PACKAGING_OUT}/conffiles)

set(CPACK_DEBIAN_HMI_PACKAGE_NAME openvcu-hmi)
set(CPACK_DEBIAN_HMI_PACKAGE_SECTION misc)
# what no linker sees: the QML modules vcu-hmi imports (QtQuick, .Controls, .Layouts) and what
# those load, and the eglfs platform plugin with its KMS integration (libqt6opengl6) that
# openvcu-hmi.service selects
set(CPACK_DEBIAN_HMI_PACKAGE_DEPENDS
    "openvcu (= ${OPENVCU_DEB_VERSION}), qml6-module-qtquick, qml6-module-qtquick-controls, qml6-module-qtquick-layouts, qml6-module-qtquick-templates, qml6-module-qtquick-window, qml6-module-qtqml-workerscript, libqt6opengl6")
set(CPACK_DEBIAN_HMI_DESCRIPTION "touchscreen dashboard of the openvcu stack
vcu-hmi is the Qt 6 Quick touchscreen HMI of an openvcu vehicle control
unit: dashboard, CAN data, ECU setup, debug and trace pages. It runs on the
display without a window system (eglfs) as the service openvcu-hmi.")
set(CPACK_DEBIAN_HMI_PACKAGE_CONTROL_EXTRA
    ${OPENVCU_PACKAGING_DIR}/openvcu-hmi/postinst ${OPENVCU_PACKAGING_DIR}/openvcu-hmi/prerm
    ${OPENVCU_PACKAGING_DIR}/openvcu-hmi/postrm)

include(CPack)
