// bench/micro/bench_mpi_calls.cpp — what one MPI call costs a real rank of this build's MPI on
// this machine (the calibration of the simulated cluster, bench/scripts/smpi_run.py; docs/smpi.md
// "What SMPI charges a rank"):
//   iprobe    one MPI_Iprobe that finds nothing (hypre's assumed-partition exchange polls so)
//   test      one MPI_Test of a receive that has not arrived
//   exchange  one MPI_Sendrecv of a double around the ring of ranks (the real counterpart of
//             smpi_empty_bursts, whose ranks do the same under the simulator)
// iprobe and test are the thread CPU time of ITERS calls (default 100000; a call that polls does
// not wait, and a shared machine's time slices are not the call's), the least of REPEATS
// (default 9) timings; exchange is wall time (it waits for the neighbour), the median. Rank 0
// prints one JSON line: {"ranks": P, "iprobe_s": ..., "test_s": ..., "exchange_s": ...}.
//   mpirun -n 2 build/bench/bench_mpi_calls [ITERS] [REPEATS]
#include <mpi.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double least(const std::vector<double>& v) {
  return *std::min_element(v.begin(), v.end());
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const long iters = argc > 1 ? std::atol(argv[1]) : 100000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 9;
  if (iters < 1 || repeats < 1) {
    if (rank == 0) std::fprintf(stderr, "bench_mpi_calls: ITERS and REPEATS must be >= 1\n");
    MPI_Finalize();
    return 2;
  }
  std::vector<double> iprobe, test, exchange;
  const int peer = (rank + 1) % size, from = (rank + size - 1) % size;
  for (int r = 0; r < repeats; ++r) {
    // MPI_Iprobe on a tag nobody sends
    MPI_Barrier(MPI_COMM_WORLD);
    int flag = 0;
    double t0 = cpuSeconds();
    for (long i = 0; i < iters; ++i)
      MPI_Iprobe(MPI_ANY_SOURCE, 99, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
    iprobe.push_back((cpuSeconds() - t0) / static_cast<double>(iters));
    // MPI_Test of a receive whose send comes after the loop
    double in = 0, out = rank;
    MPI_Request req;
    MPI_Irecv(&in, 1, MPI_DOUBLE, from, 98, MPI_COMM_WORLD, &req);
    MPI_Barrier(MPI_COMM_WORLD);
    t0 = cpuSeconds();
    for (long i = 0; i < iters; ++i) MPI_Test(&req, &flag, MPI_STATUS_IGNORE);
    test.push_back((cpuSeconds() - t0) / static_cast<double>(iters));
    MPI_Send(&out, 1, MPI_DOUBLE, peer, 98, MPI_COMM_WORLD);
    MPI_Wait(&req, MPI_STATUS_IGNORE);
    // the ring of smpi_empty_bursts
    MPI_Barrier(MPI_COMM_WORLD);
    const long ring = std::max(1L, iters / 10);
    const double w0 = MPI_Wtime();
    for (long i = 0; i < ring; ++i)
      MPI_Sendrecv(&out, 1, MPI_DOUBLE, peer, 0, &in, 1, MPI_DOUBLE, from, 0, MPI_COMM_WORLD,
                   MPI_STATUS_IGNORE);
    exchange.push_back((MPI_Wtime() - w0) / static_cast<double>(ring));
  }
  double mine[3] = {least(iprobe), least(test), median(exchange)}, worst[3];
  MPI_Reduce(mine, worst, 3, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  if (rank == 0)
    std::printf("{\"ranks\": %d, \"iprobe_s\": %.4e, \"test_s\": %.4e, \"exchange_s\": %.4e}\n",
                size, worst[0], worst[1], worst[2]);
  MPI_Finalize();
  return 0;
}
