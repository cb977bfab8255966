# The test install_example: installs this build under WORK_DIR/prefix, then configures, builds
# and runs examples/detect against it, as a project of a user would.
# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -P RunInstallExample.cmake
file(REMOVE_RECURSE ${WORK_DIR})
function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install_example: ${what} failed (${rc}):\n${out}")
  endif()
  message(STATUS "${what}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
step("configure examples/detect" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/detect
     -B ${WORK_DIR}/build -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release
     -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
step("build examples/detect" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
step("run detect_example" ${WORK_DIR}/build/detect_example)
message(STATUS "${last_output}")
