# The one way a GoogleTest program is added: contactlab_add_gtest(NAME LIBS lib... LABELS label...
# [SOURCE file] [TIMEOUT seconds] [ENVIRONMENT var=value...] [PROPERTIES prop value...]) builds
# NAME.cpp (or SOURCE) of the calling folder and registers each of its tests with CTest through
# gtest_discover_tests, with the labels, a time limit scaled by CONTACTLAB_TEST_TIME_SCALE
# (sanitized builds run slower) and tests/common on the include path.
include(GoogleTest)

# The executable both registrations build: NAME from SOURCE (default NAME.cpp) with LIBS, the
# flags and tests/common; sets `timeout` in the caller to TIMEOUT (default 120 s) scaled by
# CONTACTLAB_TEST_TIME_SCALE. A macro, so it reads the caller's parsed ARG_* values.
macro(_contactlab_test_executable name)
  if(NOT ARG_SOURCE)
    set(ARG_SOURCE ${name}.cpp)
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_executable(${name} ${ARG_SOURCE})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} contactlab::flags)
  target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}
                                             ${PROJECT_SOURCE_DIR}/tests/common)
  math(EXPR timeout "${ARG_TIMEOUT} * ${CONTACTLAB_TEST_TIME_SCALE}")
endmacro()

function(contactlab_add_gtest name)
  cmake_parse_arguments(ARG "" "SOURCE;TIMEOUT" "LIBS;LABELS;ENVIRONMENT;PROPERTIES" ${ARGN})
  _contactlab_test_executable(${name})
  target_link_libraries(${name} PRIVATE GTest::gtest_main)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT ${timeout} ${ARG_PROPERTIES})
  # gtest_discover_tests splits every property value at ';', so a second label or a second
  # variable would become a property name and shift the rest. The list-valued properties are
  # set by a script CTest includes after the discovered tests (<name>_TESTS lists them).
  set(list_properties "${CMAKE_CURRENT_BINARY_DIR}/${name}_list_properties.cmake")
  file(WRITE "${list_properties}"
       "foreach(test IN LISTS ${name}_TESTS)\n"
       "  set_tests_properties(\"\${test}\" PROPERTIES LABELS \"${ARG_LABELS}\")\n")
  if(ARG_ENVIRONMENT)
    file(APPEND "${list_properties}"
         "  set_tests_properties(\"\${test}\" PROPERTIES ENVIRONMENT \"${ARG_ENVIRONMENT}\")\n")
  endif()
  file(APPEND "${list_properties}" "endforeach()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${list_properties}")
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

# MPI tests: contactlab_add_mpi_test(NAME LIBS lib... RANKS k... [SOURCE file] [TIMEOUT seconds])
# builds NAME.cpp (or SOURCE) as a GoogleTest program with its own main (it initialises MPI)
# and registers one CTest test NAME_npK per rank count, run as `mpiexec -np K` (oversubscribed
# with Open MPI, so 4 ranks run on 2 cores), labelled mpi. CONTACTLAB_MPI_TEST_ENVIRONMENT is
# the environment of every MPI test (Open MPI refuses root without its two variables).
set(CONTACTLAB_MPI_TEST_ENVIRONMENT OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    OMP_WAIT_POLICY=passive OMPI_MCA_rmaps_base_oversubscribe=1)
# Under the address sanitizer: with several ranks Open MPI's plugins keep a few bytes each from
# the first communications until exit, in plugins unloaded at MPI_Finalize (the leak report
# cannot name them, so no suppression can); the leak check is off for these tests only, memory
# errors are still reported. (What MPI_Init and MPI_Finalize keep is left out where they are
# called, kernels/mpi/src/runtime.cpp, for every program.)
if(CONTACTLAB_SANITIZE MATCHES "address")
  list(APPEND CONTACTLAB_MPI_TEST_ENVIRONMENT ASAN_OPTIONS=detect_leaks=0)
endif()
set(CONTACTLAB_MPIEXEC_FLAGS "")
if(MPIEXEC_EXECUTABLE)
  execute_process(COMMAND ${MPIEXEC_EXECUTABLE} --version OUTPUT_VARIABLE _cl_mpiexec_version
                  ERROR_QUIET)
  if(_cl_mpiexec_version MATCHES "Open MPI|OpenRTE")
    set(CONTACTLAB_MPIEXEC_FLAGS --oversubscribe)
  endif()
endif()

# Each test's mpiexec keeps its session directory under a base of its own: two mpiexecs started
# together under `ctest -j2` race to make Open MPI's shared /tmp/ompi.HOST.UID, and the loser
# stops ("A call to mkdir was unable to create the desired directory ... File exists"; seen
# once, 2026-12-05). The base sits right under /tmp, whose existence no one races for, and is
# short: PMIx's sockets and shared segments live below it, and a socket path ends at 108 bytes.
string(MD5 _cl_build_hash "${PROJECT_BINARY_DIR}")
string(SUBSTRING "${_cl_build_hash}" 0 8 CONTACTLAB_MPI_SESSION_TAG)

function(contactlab_add_mpi_test name)
  cmake_parse_arguments(ARG "" "SOURCE;TIMEOUT" "LIBS;RANKS" ${ARGN})
  _contactlab_test_executable(${name})
  target_link_libraries(${name} PRIVATE GTest::gtest MPI::MPI_CXX)
  foreach(ranks ${ARG_RANKS})
    add_test(NAME ${name}_np${ranks}
             COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${ranks} ${CONTACTLAB_MPIEXEC_FLAGS}
                     ${MPIEXEC_PREFLAGS} $<TARGET_FILE:${name}> ${MPIEXEC_POSTFLAGS})
    set(session "/tmp/cl-${CONTACTLAB_MPI_SESSION_TAG}-${name}-np${ranks}")
    set_tests_properties(${name}_np${ranks} PROPERTIES LABELS mpi TIMEOUT ${timeout}
                         ENVIRONMENT "${CONTACTLAB_MPI_TEST_ENVIRONMENT};OMPI_MCA_orte_tmpdir_base=${session}")
  endforeach()
endfunction()
