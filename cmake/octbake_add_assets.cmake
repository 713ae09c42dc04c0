# octbake_add_assets(TARGET <name> OUTPUT_DIR <dir> FILES <mesh>...
#                    [DEPTH <n>] [OCCUPANCY surface|solid|vertices] [COMPRESS zstd[:LEVEL]|none])
#
# Bakes meshes at build time: one build rule per mesh, OUTPUT_DIR/<stem>.oct,
# so Make and Ninja bake in parallel (-j) and incrementally. Each rule's
# depfile (written by `octbake --depfile`) lists every file the importer read
# — the mesh, an OBJ's .mtl, a glTF's .bin — so editing one of them rebakes
# that mesh and nothing else; a new octbake binary rebakes everything.
# <name> becomes a custom target (part of ALL) that depends on every output;
# its property OCTBAKE_OUTPUTS lists them. Relative FILES are relative to the
# current source dir, a relative OUTPUT_DIR to the current binary dir.
# Options not given use octbake's defaults (depth 6, surface, zstd:19).
# Needs the octbake::octbake executable target: from find_package(octbake)
# (component tools) or from add_subdirectory of the octbake tree.
# Two FILES with the same stem (a/x.obj, b/x.ply) are a configure error.
function(octbake_add_assets)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "TARGET;OUTPUT_DIR;DEPTH;OCCUPANCY;COMPRESS" "FILES")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "octbake_add_assets: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
  endif()
  foreach(required TARGET OUTPUT_DIR FILES)
    if(NOT arg_${required})
      message(FATAL_ERROR "octbake_add_assets: ${required} is required")
    endif()
  endforeach()
  if(NOT TARGET octbake::octbake)
    message(FATAL_ERROR "octbake_add_assets: no octbake::octbake executable: install octbake's tools component "
                        "(find_package(octbake)) or add_subdirectory() the octbake tree first")
  endif()
  if(DEFINED arg_DEPTH AND NOT arg_DEPTH MATCHES "^([1-9]|1[0-2])$")
    message(FATAL_ERROR "octbake_add_assets: DEPTH must be 1..12, got \"${arg_DEPTH}\"")
  endif()
  if(DEFINED arg_OCCUPANCY AND NOT arg_OCCUPANCY MATCHES "^(surface|solid|vertices)$")
    message(FATAL_ERROR "octbake_add_assets: OCCUPANCY must be surface, solid or vertices, got \"${arg_OCCUPANCY}\"")
  endif()
  if(DEFINED arg_COMPRESS AND NOT arg_COMPRESS MATCHES "^(none|zstd|zstd:[0-9]+)$")
    message(FATAL_ERROR "octbake_add_assets: COMPRESS must be zstd[:LEVEL] or none, got \"${arg_COMPRESS}\"")
  endif()

  set(options -q -j 1)
  if(DEFINED arg_DEPTH)
    list(APPEND options -d ${arg_DEPTH})
  endif()
  if(DEFINED arg_OCCUPANCY)
    list(APPEND options --occupancy ${arg_OCCUPANCY})
  endif()
  if(DEFINED arg_COMPRESS)
    list(APPEND options --compress ${arg_COMPRESS})
  endif()
  get_filename_component(out_dir "${arg_OUTPUT_DIR}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  set(dep_dir "${CMAKE_CURRENT_BINARY_DIR}/octbake_depfiles/${arg_TARGET}")
  file(MAKE_DIRECTORY "${out_dir}" "${dep_dir}")

  set(outputs "")
  set(stems "")
  foreach(mesh IN LISTS arg_FILES)
    get_filename_component(mesh_abs "${mesh}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    get_filename_component(stem "${mesh_abs}" NAME_WLE)
    if(stem IN_LIST stems)
      message(FATAL_ERROR "octbake_add_assets: two FILES would both write ${out_dir}/${stem}.oct (${mesh})")
    endif()
    list(APPEND stems "${stem}")
    set(output "${out_dir}/${stem}.oct")
    set(depfile "${dep_dir}/${stem}.oct.d")
    # Depfile paths are absolute; NEW makes Ninja match them to the output
    # whatever the caller's cmake_minimum_required says.
    cmake_policy(PUSH)
    cmake_policy(SET CMP0116 NEW)
    add_custom_command(OUTPUT "${output}"
      COMMAND octbake::octbake ${options} -o "${out_dir}" --depfile "${depfile}" "${mesh_abs}"
      MAIN_DEPENDENCY "${mesh_abs}"
      DEPENDS octbake::octbake
      DEPFILE "${depfile}"
      COMMENT "octbake: baking ${stem}"
      VERBATIM)
    cmake_policy(POP)
    list(APPEND outputs "${output}")
  endforeach()
  add_custom_target(${arg_TARGET} ALL DEPENDS ${outputs})
  set_target_properties(${arg_TARGET} PROPERTIES OCTBAKE_OUTPUTS "${outputs}")
endfunction()
