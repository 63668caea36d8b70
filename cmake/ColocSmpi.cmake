# The SimGrid SMPI build (-DCOLOC_SMPI=ON, cmake/setup-smpi.sh; docs/smpi.md): coloc runs as
# hundreds of simulated ranks inside one process under `smpirun`, each rank's computation timed
# for real and each message through the network model of a platform file (bench/platforms/).
#
# The same sources as the Open MPI build, compiled by the system's C++ compiler against SMPI's
# mpi.h (smpicxx force-includes smpi_helpers.h, whose function-like macros exit(x), free(x), ...
# break C++ headers; coloc times with MPI_Wtime, which SMPI simulates). Every object is position-
# independent and `coloc` is linked as a shared object: smpirun's loader (smpimain) dlopens one
# private copy per rank, so each rank has its own globals (hypre's included).
find_path(SIMGRID_SMPI_INCLUDE_DIR smpi/mpi.h REQUIRED)
find_library(SIMGRID_LIBRARY simgrid REQUIRED)
find_program(SMPIRUN_EXECUTABLE smpirun REQUIRED)
foreach(lang C CXX)
  add_library(MPI::MPI_${lang} INTERFACE IMPORTED)
  set_target_properties(MPI::MPI_${lang} PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${SIMGRID_SMPI_INCLUDE_DIR}/smpi"
    INTERFACE_LINK_LIBRARIES "${SIMGRID_LIBRARY}")
endforeach()
set(CMAKE_POSITION_INDEPENDENT_CODE ON)

# coloc_smpi_program(target): an SMPI program is a shared object (its own sources -fPIC, not the
# PIE of an executable) that smpirun's loader dlopens once per simulated rank; -z defs makes a
# symbol missing from the libraries fail the link, not the first simulated run.
function(coloc_smpi_program target)
  target_compile_options(${target} PRIVATE -fPIC)
  target_link_options(${target} PRIVATE -shared -Wl,-z,defs)
endfunction()
if(NOT HYPRE_LIBRARY OR NOT HYPRE_INCLUDE_DIR)
  message(FATAL_ERROR "COLOC_SMPI: give -DHYPRE_LIBRARY=<libHYPRE.a built with smpicc> and "
                      "-DHYPRE_INCLUDE_DIR=<its include/> (cmake/setup-smpi.sh builds both)")
endif()
