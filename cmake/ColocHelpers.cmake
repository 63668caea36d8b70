# Helpers shared by the folders.

# Environment every MPI launch in CTest gets: mpirun as root, more ranks than cores, a rank
# waiting in MPI yields its core (tests oversubscribe a 2-core machine; README.md), and mpirun
# ends a job whose rank exited non-zero at once instead of after its default 1 s grace before
# SIGKILL, which it spends about twice (odls_base_sigkill_timeout: 2 s of every one of the ~150
# tests that expect a failure, issue 49; coloc's own stop of every rank does not depend on it).
set(COLOC_MPI_ENV OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_mpi_yield_when_idle=1
    OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_odls_base_sigkill_timeout=0)

# coloc_add_library(name SOURCES ... DEPS ...): a folder's library with its public include/.
function(coloc_add_library name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_library(coloc_${name} ${A_SOURCES})
  add_library(coloc::${name} ALIAS coloc_${name})
  target_include_directories(coloc_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(coloc_${name} PUBLIC ${A_DEPS})
endfunction()

# coloc_add_mpi_test(NAME exe RANKS 1 2 4 LABELS ... [ARGS ...] [TIMEOUT s]):
# registers `exe` once per rank count, launched through mpiexec.
function(coloc_add_mpi_test name)
  cmake_parse_arguments(A "" "TIMEOUT;TARGET" "RANKS;LABELS;ARGS" ${ARGN})
  if(NOT A_TIMEOUT)
    set(A_TIMEOUT 300)
  endif()
  if(NOT A_TARGET)
    set(A_TARGET ${name})
  endif()
  foreach(np ${A_RANKS})
    set(procs ${np})
    if(procs GREATER 2)
      set(procs 2)
    endif()
    add_test(NAME ${name}_np${np}
             COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${np} --bind-to none
                     ${MPIEXEC_PREFLAGS} $<TARGET_FILE:${A_TARGET}> ${MPIEXEC_POSTFLAGS} ${A_ARGS})
    set_tests_properties(${name}_np${np} PROPERTIES ENVIRONMENT "${COLOC_MPI_ENV}"
                         PROCESSORS ${procs} TIMEOUT ${A_TIMEOUT} LABELS "${A_LABELS}")
  endforeach()
endfunction()

# coloc_check_arrows(): the rooms' libraries link only the rooms below them, and only io links
# HDF5 (docs/architecture.md). Called once every room is added; a wrong arrow fails the configure.
function(coloc_check_arrows)
  set(allowed_core "")
  set(allowed_partition core)
  set(allowed_io core partition)
  set(allowed_fv core partition)
  set(allowed_dem core partition)
  set(allowed_coupling core partition io fv dem)
  foreach(room core partition io fv dem coupling)
    get_target_property(libs coloc_${room} LINK_LIBRARIES)
    foreach(lib ${libs})
      if(lib MATCHES "^coloc::(.+)$" AND NOT CMAKE_MATCH_1 IN_LIST allowed_${room})
        message(FATAL_ERROR "coloc_${room} links ${lib}: the arrows run core -> partition -> "
                            "{io, fv, dem} -> coupling (docs/architecture.md)")
      endif()
      if(lib MATCHES "HDF5" AND NOT room STREQUAL "io")
        message(FATAL_ERROR "coloc_${room} links ${lib}: only io links HDF5")
      endif()
    endforeach()
  endforeach()
endfunction()
