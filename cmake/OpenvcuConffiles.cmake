# cmake -DETC_DIR=<generated /etc/openvcu> -DOUT=<file> -P cmake/OpenvcuConffiles.cmake
# Writes the Debian conffiles list: /etc/openvcu/<name> for every file in ETC_DIR, sorted
# (cmake/OpenvcuPackaging.cmake runs it at build time).
if(NOT ETC_DIR OR NOT OUT)
  message(FATAL_ERROR "OpenvcuConffiles.cmake: set ETC_DIR and OUT")
endif()
file(GLOB_RECURSE files LIST_DIRECTORIES false RELATIVE ${ETC_DIR} ${ETC_DIR}/*)
if(NOT files)
  message(FATAL_ERROR "OpenvcuConffiles.cmake: ${ETC_DIR}: no files")
endif()
list(SORT files)
set(text "")
foreach(file IN LISTS files)
  string(APPEND text "/etc/openvcu/${file}\n")
endforeach()
file(WRITE ${OUT} "${text}")
