# octbake::zstd: libzstd, whether the system provides it shared or static.
# Used by the build and by the installed package config (a static runtime
# needs zstd on its consumers' link line). Prefers zstd's own CMake package
# (shared target first), then a plain find_library (libzstd.so or libzstd.a).
if(NOT TARGET octbake::zstd)
  find_package(zstd CONFIG QUIET)
  if(TARGET zstd::libzstd_shared)
    set(_octbake_zstd zstd::libzstd_shared)
  elseif(TARGET zstd::libzstd_static)
    set(_octbake_zstd zstd::libzstd_static)
  else()
    find_path(OCTBAKE_ZSTD_INCLUDE_DIR zstd.h)
    find_library(OCTBAKE_ZSTD_LIBRARY NAMES zstd libzstd.a)
    if(NOT OCTBAKE_ZSTD_INCLUDE_DIR OR NOT OCTBAKE_ZSTD_LIBRARY)
      message(FATAL_ERROR "octbake: zstd not found (install libzstd-dev, or set CMAKE_PREFIX_PATH)")
    endif()
    add_library(octbake::zstd_library UNKNOWN IMPORTED)
    set_target_properties(octbake::zstd_library PROPERTIES
      IMPORTED_LOCATION ${OCTBAKE_ZSTD_LIBRARY} INTERFACE_INCLUDE_DIRECTORIES ${OCTBAKE_ZSTD_INCLUDE_DIR})
    set(_octbake_zstd octbake::zstd_library)
  endif()
  add_library(octbake::zstd INTERFACE IMPORTED)
  target_link_libraries(octbake::zstd INTERFACE ${_octbake_zstd})
  unset(_octbake_zstd)
endif()
