# The one way a GoogleTest program is added: contactlab_add_gtest(NAME LIBS lib... LABELS label...
# [SOURCE file] [TIMEOUT seconds] [ENVIRONMENT var=value...] [PROPERTIES prop value...]) builds
# NAME.cpp (or SOURCE) of the calling folder and registers each of its tests with CTest through
# gtest_discover_tests, with the labels, a time limit scaled by CONTACTLAB_TEST_TIME_SCALE
# (sanitized builds run slower) and tests/common on the include path.
include(GoogleTest)

function(contactlab_add_gtest name)
  cmake_parse_arguments(ARG "" "SOURCE;TIMEOUT" "LIBS;LABELS;ENVIRONMENT;PROPERTIES" ${ARGN})
  if(NOT ARG_SOURCE)
    set(ARG_SOURCE ${name}.cpp)
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_executable(${name} ${ARG_SOURCE})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} contactlab::flags GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}
                                             ${PROJECT_SOURCE_DIR}/tests/common)
  math(EXPR timeout "${ARG_TIMEOUT} * ${CONTACTLAB_TEST_TIME_SCALE}")
  set(environment)
  if(ARG_ENVIRONMENT)
    set(environment ENVIRONMENT "${ARG_ENVIRONMENT}")
  endif()
  gtest_discover_tests(${name}
    DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${timeout} ${environment} ${ARG_PROPERTIES})
endfunction()

# Tests that run the contactlab programs know where they are, where the sources are (docs and
# configs are read) and which tuning cache the tune tests share.
function(contactlab_program_test name)
  target_compile_definitions(${name} PRIVATE CONTACTLAB_EXE="$<TARGET_FILE:contactlab>"
                             CONTACTLAB_CACHESIM_EXE="$<TARGET_FILE:contactlab_cachesim>"
                             CONTACTLAB_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                             CONTACTLAB_TUNE_CACHE_DIR="${PROJECT_BINARY_DIR}/tests/tune-cache")
  add_dependencies(${name} contactlab contactlab_cachesim)
endfunction()
