# FindHYPRE: locate hypre (Struct interface) and provide HYPRE::HYPRE.
# Debian ships neither HYPREConfig.cmake nor a .pc file: the config package first (other
# systems, Spack builds), else find_path/find_library (cmake/ColocFindImported.cmake).
include(ColocFindImported)
coloc_find_imported(HYPRE HYPRE_struct_ls.h HYPRE PATH_SUFFIXES hypre LINK MPI::MPI_C)
