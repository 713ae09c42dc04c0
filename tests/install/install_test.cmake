# ctest: install this build into a temporary prefix, then configure, build and
# run a consumer that only knows find_package(octbake); the same consumer
# built from pkg-config's flags; in a shared build, the libraries' dynamic
# symbol tables hold the API and none of the internals. Needs the runtime built
# first (ctest runs after the build). In sanitizer builds the consumer gets the
# same -fsanitize flags, since the installed library carries ASan/UBSan calls.
add_test(NAME install_consumer
  COMMAND ${CMAKE_COMMAND}
    -DOCTBAKE_BUILD_DIR=${PROJECT_BINARY_DIR}
    -DCONSUMER_SOURCE_DIR=${CMAKE_CURRENT_LIST_DIR}/consumer
    -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/install_test
    -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
    -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
    -DSANITIZE=${OCTBAKE_SANITIZE}
    -DSHARED=${BUILD_SHARED_LIBS}
    -DBAKER_LIB=$<$<TARGET_EXISTS:octbake_baker>:$<TARGET_FILE:octbake_baker>>
    -P ${CMAKE_CURRENT_LIST_DIR}/run_install_test.cmake)
set_tests_properties(install_consumer PROPERTIES TIMEOUT 180)
