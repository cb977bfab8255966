# FindHWLOC: locates hwloc (machine topology: caches, cores) through pkg-config.
# Defines HWLOC::hwloc and HWLOC_FOUND / HWLOC_VERSION.
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(PC_HWLOC QUIET IMPORTED_TARGET hwloc)
endif()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(HWLOC REQUIRED_VARS PC_HWLOC_FOUND VERSION_VAR PC_HWLOC_VERSION)
if(HWLOC_FOUND AND NOT TARGET HWLOC::hwloc)
  add_library(HWLOC::hwloc ALIAS PkgConfig::PC_HWLOC)
  set(HWLOC_VERSION ${PC_HWLOC_VERSION})
endif()
