# Build description (compiler, flags, git commit) compiled into contactlab::build_info, so every
# result file records what produced it. The commit is re-read at every build, not only at configure.
get_target_property(_cl_opts contactlab_flags INTERFACE_COMPILE_OPTIONS)
string(TOUPPER "${CMAKE_BUILD_TYPE}" _cl_bt)
set(CONTACTLAB_FLAGS_STRING "${CMAKE_CXX_FLAGS} ${CMAKE_CXX_FLAGS_${_cl_bt}} ${_cl_opts}")
string(REPLACE ";" " " CONTACTLAB_FLAGS_STRING "${CONTACTLAB_FLAGS_STRING}")
set(_cl_out ${CMAKE_CURRENT_BINARY_DIR}/generated/build_info.cpp)
add_custom_target(contactlab_build_info_gen
  BYPRODUCTS ${_cl_out}
  COMMAND ${CMAKE_COMMAND} -DOUT=${_cl_out} -DSRC=${CMAKE_CURRENT_SOURCE_DIR}
          "-DCOMPILER=${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}"
          "-DFLAGS=${CONTACTLAB_FLAGS_STRING}" -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
          -DNATIVE=${CONTACTLAB_NATIVE} -DVERSION=${PROJECT_VERSION}
          -P ${CMAKE_CURRENT_SOURCE_DIR}/cmake/WriteBuildInfo.cmake
  VERBATIM)
