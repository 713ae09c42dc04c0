# octbake_add_startup_test(NAME <name> SCENE <scene.json> BUDGET <budget.json>
#                          [BAKED <dir or pack>] [OCTSCENE <executable>])
#
# Adds a ctest that loads SCENE with `octscene run --frames 0 --budget BUDGET`
# and fails when a deterministic start-up counter (files opened, bytes
# mapped, levels decoded, bytes decompressed, heap allocations during load)
# exceeds the committed budget; the test's output names each counter over
# budget. Record a budget with
#   octscene run SCENE --frames 0 --write-budget BUDGET
# BAKED overrides the scene's "baked" folder (e.g. files baked at build time);
# it is passed as written, relative to the test's working directory (the
# calling folder's build directory). heap_allocations depends slightly on the
# length of that path (std::string growth), so give BAKED as a relative path
# for a count that is the same in every checkout; without BAKED the scene's
# own "baked" is used, resolved against the scene's absolute path.
# OCTSCENE is the driver to use; by default the imported target
# octbake::octscene (from find_package(octbake)), else the in-tree target
# octscene. SCENE and BUDGET are relative to the calling CMakeLists.txt's folder.
function(octbake_add_startup_test)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "NAME;SCENE;BUDGET;BAKED;OCTSCENE" "")
  foreach(required NAME SCENE BUDGET)
    if(NOT arg_${required})
      message(FATAL_ERROR "octbake_add_startup_test: ${required} is required")
    endif()
  endforeach()
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "octbake_add_startup_test: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
  endif()
  if(arg_OCTSCENE)
    set(octscene "${arg_OCTSCENE}")
  elseif(TARGET octbake::octscene)
    set(octscene "$<TARGET_FILE:octbake::octscene>")
  elseif(TARGET octscene)
    set(octscene "$<TARGET_FILE:octscene>")
  else()
    message(FATAL_ERROR "octbake_add_startup_test: no octscene executable "
                        "(find_package(octbake) provides octbake::octscene, or pass OCTSCENE)")
  endif()
  get_filename_component(scene "${arg_SCENE}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  get_filename_component(budget "${arg_BUDGET}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  set(command "${octscene}" run "${scene}" --frames 0 --budget "${budget}")
  if(arg_BAKED)
    list(APPEND command --baked "${arg_BAKED}")
  endif()
  add_test(NAME ${arg_NAME} COMMAND ${command} WORKING_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}")
endfunction()
