# coloc_find_imported(PKG HEADER LIBRARY [PATH_SUFFIXES ...] [LINK ...]): the body of a Find
# module for a library that Debian ships without a CMake package (FindHYPRE, FindSLEEF). Tries
# the config package first (other systems, Spack builds), then find_path / find_library, and
# provides the imported target PKG::PKG (LINK: its interface link libraries). A macro: the
# variables it sets (PKG_FOUND, PKG_INCLUDE_DIR, PKG_LIBRARY) belong to the Find module's scope.
include(FindPackageHandleStandardArgs)
macro(coloc_find_imported pkg header library)
  cmake_parse_arguments(_cfi "" "" "PATH_SUFFIXES;LINK" ${ARGN})
  find_package(${pkg} CONFIG QUIET NO_MODULE)
  if(NOT TARGET ${pkg}::${pkg})
    find_path(${pkg}_INCLUDE_DIR ${header} PATH_SUFFIXES ${_cfi_PATH_SUFFIXES})
    find_library(${pkg}_LIBRARY NAMES ${library})
    find_package_handle_standard_args(${pkg} REQUIRED_VARS ${pkg}_LIBRARY ${pkg}_INCLUDE_DIR)
    if(${pkg}_FOUND)
      add_library(${pkg}::${pkg} UNKNOWN IMPORTED)
      set_target_properties(${pkg}::${pkg} PROPERTIES IMPORTED_LOCATION "${${pkg}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${${pkg}_INCLUDE_DIR}")
      if(_cfi_LINK)
        set_target_properties(${pkg}::${pkg} PROPERTIES INTERFACE_LINK_LIBRARIES "${_cfi_LINK}")
      endif()
    endif()
  else()
    set(${pkg}_FOUND TRUE)
  endif()
endmacro()
