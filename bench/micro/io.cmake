# Parallel HDF5 output: collective write/read of a cell field, particle arrays.
#   mpirun -n 2 build/bench/bench_io        (files go to $COLOC_BENCH_DIR, default /tmp)
add_executable(bench_io ${CMAKE_CURRENT_LIST_DIR}/bench_io.cpp ${CMAKE_CURRENT_LIST_DIR}/bench_main.cpp)
target_link_libraries(bench_io PRIVATE coloc::io benchmark::benchmark)
set_target_properties(bench_io PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bench)
coloc_bench_smoke(bench_io 2 "BM_WriteCellField/64/|BM_ReadCellField/64/")
