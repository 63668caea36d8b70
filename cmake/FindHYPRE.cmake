# FindHYPRE: locate hypre (Struct interface) and provide HYPRE::HYPRE.
# Debian ships neither HYPREConfig.cmake nor a .pc file, so try the config package first
# (other systems, Spack builds) and fall back to find_path/find_library.
find_package(HYPRE CONFIG QUIET NO_MODULE)
if(NOT TARGET HYPRE::HYPRE)
  find_path(HYPRE_INCLUDE_DIR HYPRE_struct_ls.h PATH_SUFFIXES hypre)
  find_library(HYPRE_LIBRARY NAMES HYPRE)
  include(FindPackageHandleStandardArgs)
  find_package_handle_standard_args(HYPRE REQUIRED_VARS HYPRE_LIBRARY HYPRE_INCLUDE_DIR)
  if(HYPRE_FOUND)
    add_library(HYPRE::HYPRE UNKNOWN IMPORTED)
    set_target_properties(HYPRE::HYPRE PROPERTIES IMPORTED_LOCATION "${HYPRE_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${HYPRE_INCLUDE_DIR}" INTERFACE_LINK_LIBRARIES MPI::MPI_C)
  endif()
else()
  set(HYPRE_FOUND TRUE)
endif()
