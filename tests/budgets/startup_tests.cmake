# The start-up budget of the bundled thesis scene, checked through the same
# helper apps use (cmake/octbake_startup_test.cmake). The assets are baked
# into the build tree first (a ctest fixture) with octbake's defaults.
include(${PROJECT_SOURCE_DIR}/cmake/octbake_startup_test.cmake)

file(GLOB startup_assets CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/assets/*.obj)
set(startup_baked ${CMAKE_CURRENT_BINARY_DIR}/startup_baked)
add_test(NAME startup_bake_assets COMMAND octbake -q --force -o ${startup_baked} ${startup_assets})
set_tests_properties(startup_bake_assets PROPERTIES FIXTURES_SETUP startup_baked)

octbake_add_startup_test(NAME startup_budget_test1
  SCENE ${PROJECT_SOURCE_DIR}/assets/scenes/test1.json
  BUDGET ${CMAKE_CURRENT_LIST_DIR}/test1_startup.json
  BAKED startup_baked)  # relative: the same heap count in every checkout
set_tests_properties(startup_budget_test1 PROPERTIES FIXTURES_REQUIRED startup_baked)
