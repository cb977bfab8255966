# FindCairo: locates cairo (2D drawing, PNG output) through pkg-config.
# Defines Cairo::cairo and Cairo_FOUND / Cairo_VERSION.
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(PC_CAIRO QUIET IMPORTED_TARGET cairo)
endif()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(Cairo REQUIRED_VARS PC_CAIRO_FOUND VERSION_VAR PC_CAIRO_VERSION)
if(Cairo_FOUND AND NOT TARGET Cairo::cairo)
  add_library(Cairo::cairo ALIAS PkgConfig::PC_CAIRO)
  set(Cairo_VERSION ${PC_CAIRO_VERSION})
endif()
