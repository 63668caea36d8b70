# DEM microbenchmarks: contact kernels, neighbour build, force loop, and the settled bed.
add_executable(bench_dem micro/bench_dem.cpp micro/bench_main.cpp)
target_link_libraries(bench_dem PRIVATE coloc::dem benchmark::benchmark)
target_include_directories(bench_dem PRIVATE ${PROJECT_SOURCE_DIR}/dem/src)
target_compile_definitions(bench_dem PRIVATE COLOC_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
set_target_properties(bench_dem PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bench)
coloc_bench_smoke(bench_dem 1 "BM_Contact.*/4096|BM_NeighbourBuild/10000/|BM_ForceLoop/10000/")
