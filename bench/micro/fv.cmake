# Fluid microbenchmarks (issue 3): the pressure solve (hypre Struct PCG + PFMG/SMG) and one full
# fluid step of the channel case bench/cases/fluid-channel.json at several sizes.
add_executable(bench_fv micro/bench_fv.cpp micro/bench_main.cpp)
target_link_libraries(bench_fv PRIVATE coloc::fv benchmark::benchmark)
target_include_directories(bench_fv PRIVATE ${PROJECT_SOURCE_DIR}/fv/src)
target_compile_definitions(bench_fv PRIVATE COLOC_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
set_target_properties(bench_fv PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bench)
coloc_bench_smoke(bench_fv 1 "BM_PressureSolve/32/0|BM_FluidChannelStep/10/")
