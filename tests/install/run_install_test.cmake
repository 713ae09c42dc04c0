# cmake -P script behind the install_consumer test (see install_test.cmake).
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
    OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})

# Only the library package: the tools' install rules need the tools built.
run(${CMAKE_COMMAND} --install ${OCTBAKE_BUILD_DIR} --prefix ${prefix} --component runtime)
foreach(f include/octbake.h include/octbake/world.h include/octbake/version.h include/octbake/export.h
          lib/pkgconfig/octbake.pc lib/cmake/octbake/octbake_add_assets.cmake)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

set(flags "")
if(SANITIZE)
  set(flags -DCMAKE_CXX_FLAGS=-fsanitize=address,undefined -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined)
endif()
run(${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${build}
  -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=${BUILD_TYPE} ${flags})
run(${CMAKE_COMMAND} --build ${build})
run(${build}/consumer)

# Then the baking library on top: octbake::baker from the same package, its
# private dependencies (assimp, for a static baker) found by the config.
run(${CMAKE_COMMAND} --install ${OCTBAKE_BUILD_DIR} --prefix ${prefix} --component baker)
run(${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${build}-baker -DWITH_BAKER=ON
  -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=${BUILD_TYPE} ${flags})
run(${CMAKE_COMMAND} --build ${build}-baker --target bake_consumer)
run(${build}-baker/bake_consumer)

# pkg-config: the same program from `pkg-config --cflags --libs octbake`.
find_program(PKG_CONFIG pkg-config)
if(PKG_CONFIG)
  set(ENV{PKG_CONFIG_PATH} ${prefix}/lib/pkgconfig)
  run(${PKG_CONFIG} --cflags --libs octbake)
  separate_arguments(pc_flags UNIX_COMMAND "${run_output}")
  set(pc_exe ${WORK_DIR}/consumer_pkgconfig)
  set(pc_extra "")
  if(SANITIZE)
    set(pc_extra -fsanitize=address,undefined)
  endif()
  run(${CXX_COMPILER} -std=c++20 ${pc_extra} ${CONSUMER_SOURCE_DIR}/main.cpp -o ${pc_exe} ${pc_flags}
      -Wl,-rpath,${prefix}/lib)
  run(${pc_exe})
endif()

# A shared library exports its API and hides its internals.
if(SHARED)
  run(nm -D -C --defined-only ${prefix}/lib/liboctbake_runtime.so)
  set(symbols "${run_output}")
  foreach(wanted "octbake::BakedFile::open" "octbake::World::step" "octbake::collide(")
    string(FIND "${symbols}" "${wanted}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "liboctbake_runtime.so does not export ${wanted}")
    endif()
  endforeach()
  foreach(hidden "octbake::detail::" "(anonymous namespace)")
    string(FIND "${symbols}" "${hidden}" at)
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "liboctbake_runtime.so exports internals (${hidden}):\n${symbols}")
    endif()
  endforeach()
  if(BAKER_LIB)
    run(nm -D -C --defined-only ${BAKER_LIB})
    foreach(wanted "octbake::bake_to_memory" "octbake::load_mesh")
      string(FIND "${run_output}" "${wanted}" at)
      if(at EQUAL -1)
        message(FATAL_ERROR "${BAKER_LIB} does not export ${wanted}")
      endif()
    endforeach()
    foreach(hidden "octbake::import_mesh" "octbake::run_bake" "octbake::build_tree" "RecordingIOSystem")
      string(FIND "${run_output}" "${hidden}" at)
      if(NOT at EQUAL -1)
        message(FATAL_ERROR "${BAKER_LIB} exports internals (${hidden})")
      endif()
    endforeach()
  endif()
endif()
message(STATUS "install consumer: ok")
