# ctest: a project baking its models with octbake_add_assets(), with Ninja and
# with Make, from the install tree and through add_subdirectory.
find_program(OCTBAKE_NINJA ninja)
set(generators "Unix Makefiles")
if(OCTBAKE_NINJA)
  list(APPEND generators Ninja)
endif()
foreach(generator IN LISTS generators)
  string(REPLACE "Unix Makefiles" "make" short "${generator}")
  string(TOLOWER "${short}" short)
  # add_subdirectory builds its own baker (unoptimised, to keep it short): not
  # repeated under the sanitizers, where it would test nothing new.
  set(modes install)
  if(NOT OCTBAKE_SANITIZE)
    list(APPEND modes subdir)
  endif()
  foreach(mode IN LISTS modes)
    add_test(NAME assets_${short}_${mode}
      COMMAND ${CMAKE_COMMAND}
        -DGENERATOR=${generator} -DMODE=${mode}
        -DOCTBAKE_BUILD_DIR=${PROJECT_BINARY_DIR} -DOCTBAKE_SOURCE_DIR=${PROJECT_SOURCE_DIR}
        -DPROJECT_DIR=${CMAKE_CURRENT_LIST_DIR}/assets_project
        -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/assets_${short}_${mode}
        -DCXX_COMPILER=${CMAKE_CXX_COMPILER} -DLAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER}
        -P ${CMAKE_CURRENT_LIST_DIR}/run_assets_test.cmake)
    set_tests_properties(assets_${short}_${mode} PROPERTIES TIMEOUT 1200)
  endforeach()
endforeach()
