# FindSLEEF: locate SLEEF (vectorised libm; Debian: libsleef-dev) and provide SLEEF::SLEEF.
# Debian ships a sleef.pc but no CMake package; the header lies in the multiarch include folder.
find_package(SLEEF CONFIG QUIET NO_MODULE)
if(NOT TARGET SLEEF::SLEEF)
  find_path(SLEEF_INCLUDE_DIR sleef.h)
  find_library(SLEEF_LIBRARY NAMES sleef)
  include(FindPackageHandleStandardArgs)
  find_package_handle_standard_args(SLEEF REQUIRED_VARS SLEEF_LIBRARY SLEEF_INCLUDE_DIR)
  if(SLEEF_FOUND)
    add_library(SLEEF::SLEEF UNKNOWN IMPORTED)
    set_target_properties(SLEEF::SLEEF PROPERTIES IMPORTED_LOCATION "${SLEEF_LIBRARY}"
                          INTERFACE_INCLUDE_DIRECTORIES "${SLEEF_INCLUDE_DIR}")
  endif()
endif()
