// bench/smpi/empty_bursts.cpp — a rank that does nothing between MPI calls: each of its bursts
// is SMPI's own work and the timing of it (burst_charge.cpp). The ranks pass one double around
// a ring ITERS times (default 20000); rank 0 prints the simulated time an exchange. Run under
// smpirun with COLOC_SMPI_BURST_STATS=FILE to measure the charge of an empty burst.
// `smpi_empty_bursts ITERS iprobe`: instead, each rank polls ITERS times with an MPI_Iprobe that
// finds nothing (what SMPI charges one poll; bench/results/smpi/poll-sensitivity).
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int iters = argc > 1 ? std::atoi(argv[1]) : 20000;
  const bool polls = argc > 2 && std::strcmp(argv[2], "iprobe") == 0;
  double x = rank, y = 0;
  int flag = 0;
  const double t0 = MPI_Wtime();
  for (int it = 0; it < iters; ++it) {
    if (polls)
      MPI_Iprobe(MPI_ANY_SOURCE, 7, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
    else
      MPI_Sendrecv(&x, 1, MPI_DOUBLE, (rank + 1) % size, 0, &y, 1, MPI_DOUBLE,
                   (rank + size - 1) % size, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  }
  const double t = MPI_Wtime() - t0;
  double tMax = 0;
  MPI_Reduce(&t, &tMax, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  if (rank == 0)
    std::printf("smpi_empty_bursts: %d ranks, %d %s: %.4f us %s (simulated)\n", size, iters,
                polls ? "polls" : "exchanges", 1e6 * tMax / iters,
                polls ? "a poll" : "an exchange");
  MPI_Finalize();
  return 0;
}
