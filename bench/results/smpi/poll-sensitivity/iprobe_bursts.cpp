// A rank that only polls (MPI_Iprobe that finds nothing, ITERS times): what SMPI charges one
// poll. Build: smpicxx -O2 -o iprobe_bursts iprobe_bursts.cpp; run under smpirun with
// libcoloc_smpi_burst.so preloaded and COLOC_SMPI_BURST_STATS=FILE (as smpi_run.py measures
// the empty burst of smpi_empty_bursts).
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int iters = argc > 1 ? std::atoi(argv[1]) : 20000;
  int flag = 0;
  MPI_Status st;
  const double t0 = MPI_Wtime();
  for (int it = 0; it < iters; ++it) MPI_Iprobe(MPI_ANY_SOURCE, 7, MPI_COMM_WORLD, &flag, &st);
  const double t = MPI_Wtime() - t0;
  if (rank == 0)
    std::printf("%d ranks, %d polls: %.4f us a poll (simulated)\n", size, iters, 1e6 * t / iters);
  MPI_Finalize();
  return 0;
}
