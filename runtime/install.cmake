# Installs the runtime as a CMake package:
#   find_package(octbake) + target_link_libraries(app PRIVATE octbake::runtime)
# Headers: octbake.h and octbake/*.h (they include only Eigen and the standard
# library). The static library needs zstd at link time; FlatBuffers is used
# header-only and assimp not at all, so neither is a dependency of the package.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# A static library's private dependencies still reach its consumers' link line.
target_link_libraries(octbake_runtime PRIVATE $<INSTALL_INTERFACE:zstd::libzstd_shared>)

# Everything here is component "runtime": `cmake --install B --component runtime`
# installs the library package alone, whatever tools the build also installs.
install(TARGETS octbake_runtime EXPORT octbakeTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime)
install(FILES ${CMAKE_CURRENT_SOURCE_DIR}/include/octbake.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT runtime)
install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/octbake DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  COMPONENT runtime FILES_MATCHING PATTERN "*.h")
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/include/octbake/version.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/octbake
  COMPONENT runtime)

set(octbake_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/octbake)
install(EXPORT octbakeTargets NAMESPACE octbake:: DESTINATION ${octbake_cmake_dir} COMPONENT runtime)
configure_package_config_file(${CMAKE_CURRENT_SOURCE_DIR}/cmake/octbakeConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/octbakeConfig.cmake INSTALL_DESTINATION ${octbake_cmake_dir})
# 0.x: minor versions may break the API, so only the same minor is compatible.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/octbakeConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/octbakeConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/octbakeConfigVersion.cmake
  DESTINATION ${octbake_cmake_dir} COMPONENT runtime)
