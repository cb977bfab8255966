# FindPAPI: locates the PAPI performance-counter library through pkg-config.
# Defines PAPI::papi and PAPI_FOUND / PAPI_VERSION.
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(PC_PAPI QUIET IMPORTED_TARGET papi)
endif()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(PAPI REQUIRED_VARS PC_PAPI_FOUND VERSION_VAR PC_PAPI_VERSION)
if(PAPI_FOUND AND NOT TARGET PAPI::papi)
  add_library(PAPI::papi ALIAS PkgConfig::PC_PAPI)
  set(PAPI_VERSION ${PC_PAPI_VERSION})
endif()
