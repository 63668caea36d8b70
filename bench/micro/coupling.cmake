# Coupling microbenchmarks (issue 6): stencils, deposition, interpolation, drag laws,
# 1e5 particles on a 64^3 block.   build/bench/bench_coupling
add_executable(bench_coupling micro/bench_coupling.cpp micro/bench_main.cpp)
target_link_libraries(bench_coupling PRIVATE coloc::coupling benchmark::benchmark)
set_target_properties(bench_coupling PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bench)
# Smoke test (label bench): every benchmark once, briefly, so that it cannot rot. bench/ is added
# before the top-level enable_testing(), so testing is enabled here too (else add_test is ignored).
if(COLOC_BUILD_TESTS)
  enable_testing()
  add_test(NAME bench_coupling_smoke COMMAND ${MPIEXEC_EXECUTABLE} -n 1 --bind-to none
           $<TARGET_FILE:bench_coupling> --benchmark_min_time=0.01)
  set_tests_properties(bench_coupling_smoke PROPERTIES ENVIRONMENT "${COLOC_MPI_ENV}"
                       PROCESSORS 1 LABELS bench TIMEOUT 120)
endif()
