# Install rules of the runtime, and the package config every component shares:
#   find_package(octbake [COMPONENTS baker tools])
#   target_link_libraries(app PRIVATE octbake::runtime)   # component runtime
#   target_link_libraries(app PRIVATE octbake::baker)     # component baker
#   octbake_add_assets(...)                               # needs octbake::octbake (tools)
# Components: `runtime` (library, headers, package config, pkg-config file),
# `baker` (library + octbake/baker.h, see baker/CMakeLists.txt) and `tools`
# (the octbake and octscene executables). `cmake --install B --component runtime`
# installs the library package alone.
# Headers include only Eigen and the standard library. A static runtime needs
# zstd at link time (found again by the package config, shared or static);
# FlatBuffers is used header-only and assimp not at all.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS octbake_runtime EXPORT octbakeTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT runtime
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(FILES ${CMAKE_CURRENT_SOURCE_DIR}/include/octbake.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT runtime)
install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/octbake DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  COMPONENT runtime FILES_MATCHING PATTERN "*.h")
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/include/octbake/version.h ${CMAKE_CURRENT_BINARY_DIR}/include/octbake/export.h
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/octbake COMPONENT runtime)

set(OCTBAKE_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/octbake CACHE INTERNAL "")
install(EXPORT octbakeTargets NAMESPACE octbake:: DESTINATION ${OCTBAKE_CMAKE_INSTALL_DIR} COMPONENT runtime)
# The package config records how the runtime was built (static: find zstd).
if(BUILD_SHARED_LIBS)
  set(OCTBAKE_SHARED ON)
else()
  set(OCTBAKE_SHARED OFF)
endif()
configure_package_config_file(${CMAKE_CURRENT_SOURCE_DIR}/cmake/octbakeConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/octbakeConfig.cmake INSTALL_DESTINATION ${OCTBAKE_CMAKE_INSTALL_DIR})
# 0.x: minor versions may break the API, so only the same minor is compatible.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/octbakeConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
# The CMake modules of the package (cmake/*.cmake at the top of the tree:
# zstd lookup, octbake_add_assets, and whatever else lives there).
file(GLOB octbake_cmake_modules ${PROJECT_SOURCE_DIR}/cmake/*.cmake)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/octbakeConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/octbakeConfigVersion.cmake
  ${octbake_cmake_modules} DESTINATION ${OCTBAKE_CMAKE_INSTALL_DIR} COMPONENT runtime)

# pkg-config: `pkg-config --cflags --libs octbake`.
# A static runtime is the only artefact, so zstd goes on the plain Libs line
# (most users never pass --static); a shared one links zstd itself.
if(BUILD_SHARED_LIBS)
  set(OCTBAKE_PC_CFLAGS "")
  set(OCTBAKE_PC_LIBS "-loctbake_runtime")
  set(OCTBAKE_PC_LIBS_PRIVATE "-lzstd")
else()
  set(OCTBAKE_PC_CFLAGS "-DOCTBAKE_STATIC_DEFINE")
  set(OCTBAKE_PC_LIBS "-loctbake_runtime -lzstd")
  set(OCTBAKE_PC_LIBS_PRIVATE "")
endif()
file(RELATIVE_PATH OCTBAKE_PC_TO_PREFIX /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" OCTBAKE_PC_TO_PREFIX "${OCTBAKE_PC_TO_PREFIX}")
configure_file(${CMAKE_CURRENT_SOURCE_DIR}/cmake/octbake.pc.in ${CMAKE_CURRENT_BINARY_DIR}/octbake.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/octbake.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT runtime)
