# The test portable_isa_compiles: the DEM step's instruction-set passes (engine_isa.cpp, whose
# target regions add to or take from the file's baseline) compile, warnings as errors, in a
# portable build for the x86-64 baselines users name: the default (x86-64), x86-64-v2 and
# x86-64-v3 (an AVX2 cluster image, the 16-core machine's pack). Under -march=x86-64-v3 the
# baseline pass once failed to inline an intrinsic of the file's AVX2 target.
# cmake -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -P CheckPortableIsa.cmake
file(REMOVE_RECURSE ${WORK_DIR})
foreach(march x86-64 x86-64-v2 x86-64-v3)
  set(dir ${WORK_DIR}/${march})
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${dir} -G ${GENERATOR}
                          -DCMAKE_BUILD_TYPE=Release -DCONTACTLAB_NATIVE=OFF
                          -DCMAKE_CXX_FLAGS=-march=${march} -DCONTACTLAB_WERROR=ON
                          -DBUILD_TESTING=OFF
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "portable_isa_compiles: configuring -march=${march} failed:\n${out}")
  endif()
  # The one object: with Ninja a file is a target; other generators build the library.
  set(target contactlab_dem)
  if(GENERATOR STREQUAL "Ninja")
    set(target kernels/dem/CMakeFiles/contactlab_dem.dir/src/engine_isa.cpp.o)
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${dir} --target ${target}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "portable_isa_compiles: engine_isa.cpp under -march=${march}:\n${out}")
  endif()
  message(STATUS "-march=${march}: engine_isa.cpp compiles")
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
