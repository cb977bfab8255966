# `cmake --install` puts the libraries, their headers, the two programs and a package config
# under the prefix, so that another project can `find_package(contactlab)` and link
# contactlab::kernels (detection), contactlab::support (strict JSON reading, statistics),
# contactlab::tuner_model and contactlab::tuner
# (examples/detect shows it; the test `install_example` builds it).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(_cl_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/contactlab)
set_target_properties(contactlab_flags PROPERTIES EXPORT_NAME flags)
set_target_properties(contactlab_kernels PROPERTIES EXPORT_NAME kernels)
set_target_properties(contactlab_support PROPERTIES EXPORT_NAME support)
set_target_properties(contactlab_tuner_model PROPERTIES EXPORT_NAME tuner_model)
set_target_properties(contactlab_tuner PROPERTIES EXPORT_NAME tuner)
install(TARGETS contactlab_flags contactlab_kernels contactlab_support contactlab_tuner_model
                contactlab_tuner
        EXPORT contactlabTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS contactlab contactlab_cachesim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(_cl_include kernels/include kernels/support/include tuner/model/include tuner/include)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${_cl_include}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()
install(EXPORT contactlabTargets NAMESPACE contactlab:: DESTINATION ${_cl_cmake_dir})
# The optional dependencies are found again by the consumer with the same find modules.
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/contactlabConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/contactlabConfig.cmake
                              INSTALL_DESTINATION ${_cl_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/contactlabConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/contactlabConfig.cmake
              ${PROJECT_BINARY_DIR}/contactlabConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindPAPI.cmake ${PROJECT_SOURCE_DIR}/cmake/FindHWLOC.cmake
        DESTINATION ${_cl_cmake_dir})
