# The tests kernels_layer and kernels_layer_self_test: kernels/ (the science: contactlab::kernels,
# support, dem, mpi) depends on nothing above it, so no file under it includes a tuner header
# (contactlab/tuner/, tuner_model/, tuner_dem/) and no CMake file there names a tuner target.
#   cmake -DSOURCE_DIR=<checkout> -P CheckLayers.cmake      fails listing every offender
#   cmake -DWORK_DIR=<scratch> -DSELF_TEST=ON -P CheckLayers.cmake
#                                                           plants offenders; fails unless found
cmake_minimum_required(VERSION 3.25)

# Sets `out` to one line per offender under root/kernels: "file: the line".
function(kernels_layer_offenders root out)
  file(GLOB_RECURSE sources LIST_DIRECTORIES false
       "${root}/kernels/*.cpp" "${root}/kernels/*.hpp" "${root}/kernels/*.h"
       "${root}/kernels/*.cc" "${root}/kernels/*.inl")
  file(GLOB_RECURSE cmake_files LIST_DIRECTORIES false
       "${root}/kernels/CMakeLists.txt" "${root}/kernels/*.cmake")
  set(found "")
  foreach(path IN LISTS sources)
    file(STRINGS "${path}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]contactlab/tuner")
    foreach(line IN LISTS lines)
      file(RELATIVE_PATH name "${root}" "${path}")
      string(STRIP "${line}" line)
      list(APPEND found "${name}: ${line}")
    endforeach()
  endforeach()
  foreach(path IN LISTS cmake_files)
    file(STRINGS "${path}" lines REGEX "contactlab(::|_)tuner")
    foreach(line IN LISTS lines)
      string(REGEX REPLACE "^[ \t]*#.*" "" code "${line}")  # comments may name the tuner
      if(code MATCHES "contactlab(::|_)tuner")
        file(RELATIVE_PATH name "${root}" "${path}")
        string(STRIP "${line}" line)
        list(APPEND found "${name}: ${line}")
      endif()
    endforeach()
  endforeach()
  set(${out} "${found}" PARENT_SCOPE)
endfunction()

if(SELF_TEST)
  # Two offenders (an include, a link) among what must pass: a support include, an include
  # commented out, a comment naming the tuner in a CMake file.
  file(REMOVE_RECURSE "${WORK_DIR}")
  file(WRITE "${WORK_DIR}/kernels/dem/src/bad.cpp"
       "#include \"contactlab/support/statistics.hpp\"\n"
       "// #include \"contactlab/tuner/json_reader.hpp\"\n"
       "  #  include <contactlab/tuner_model/schedule_model.hpp>\n")
  file(WRITE "${WORK_DIR}/kernels/mpi/CMakeLists.txt"
       "# not contactlab::tuner\n"
       "target_link_libraries(x PRIVATE contactlab::support contactlab::tuner_model)\n")
  kernels_layer_offenders("${WORK_DIR}" found)
  list(LENGTH found count)
  if(NOT count EQUAL 2 OR NOT found MATCHES "bad.cpp: #  include <contactlab/tuner_model/"
     OR NOT found MATCHES "mpi/CMakeLists.txt: target_link_libraries")
    message(FATAL_ERROR "kernels_layer_self_test: expected the two planted offenders, found "
                        "${count}:\n${found}")
  endif()
  message(STATUS "kernels_layer_self_test: both planted offenders found")
  return()
endif()

kernels_layer_offenders("${SOURCE_DIR}" found)
if(found)
  list(LENGTH found count)
  list(JOIN found "\n  " listing)
  message(FATAL_ERROR "kernels_layer: ${count} place(s) under kernels/ depend on the tuner, which "
                      "sits above it (move the code to tuner/, or what both need to "
                      "kernels/support):\n  ${listing}")
endif()
message(STATUS "kernels_layer: nothing under kernels/ includes a tuner header or links a tuner "
               "target")
