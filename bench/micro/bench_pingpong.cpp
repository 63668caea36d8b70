// bench_pingpong: MPI ping-pong between ranks 0 and 1 for message sizes 8 B .. 4 MiB; prints a
// table and, with --json FILE, the fitted latency-bandwidth model t(n) = alpha + n / beta (one-way
// time, least squares over the sizes) that bench/scripts/model.py takes as a network profile.
//   mpirun -n 2 build/bench/bench_pingpong --json bench/results/model/pingpong.json
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::string json;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--json") == 0) json = argv[i + 1];
  if (size < 2) {
    if (rank == 0) std::fprintf(stderr, "bench_pingpong: needs 2 ranks\n");
    MPI_Finalize();
    return 2;
  }
  std::vector<char> buf(4u << 20);
  std::vector<double> sizes, times;
  for (std::size_t n = 8; n <= buf.size(); n *= 4) {
    const int reps = n < 65536 ? 2000 : 100;
    double best = 1e300;
    for (int trial = 0; trial < 5; ++trial) {  // the best of 5: the machine is shared
      MPI_Barrier(MPI_COMM_WORLD);
      const double t0 = MPI_Wtime();
      for (int r = 0; r < reps && rank < 2; ++r) {
        if (rank == 0) {
          MPI_Send(buf.data(), static_cast<int>(n), MPI_CHAR, 1, 0, MPI_COMM_WORLD);
          MPI_Recv(buf.data(), static_cast<int>(n), MPI_CHAR, 1, 0, MPI_COMM_WORLD,
                   MPI_STATUS_IGNORE);
        } else {
          MPI_Recv(buf.data(), static_cast<int>(n), MPI_CHAR, 0, 0, MPI_COMM_WORLD,
                   MPI_STATUS_IGNORE);
          MPI_Send(buf.data(), static_cast<int>(n), MPI_CHAR, 0, 0, MPI_COMM_WORLD);
        }
      }
      best = std::min(best, (MPI_Wtime() - t0) / (2.0 * reps));
    }
    sizes.push_back(static_cast<double>(n));
    times.push_back(best);
  }
  if (rank == 0) {
    // Least squares of t = alpha + n / beta, weighted by 1/t (relative errors).
    double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < sizes.size(); ++i) {
      const double w = 1.0 / (times[i] * times[i]);
      sw += w;
      sx += w * sizes[i];
      sy += w * times[i];
      sxx += w * sizes[i] * sizes[i];
      sxy += w * sizes[i] * times[i];
    }
    const double slope = (sw * sxy - sx * sy) / (sw * sxx - sx * sx);
    const double alpha = (sy - slope * sx) / sw;
    std::printf("%12s %14s %12s\n", "bytes", "one-way (us)", "GB/s");
    for (std::size_t i = 0; i < sizes.size(); ++i)
      std::printf("%12.0f %14.3f %12.3f\n", sizes[i], times[i] * 1e6, sizes[i] / times[i] / 1e9);
    std::printf("fit: latency %.3f us, bandwidth %.3f GB/s\n", alpha * 1e6, 1e-9 / slope);
    if (!json.empty()) {
      if (FILE* f = std::fopen(json.c_str(), "w")) {
        std::fprintf(f, "{\n \"latency_s\": %.6e,\n \"bandwidth_Bps\": %.6e,\n \"sizes\": [", alpha,
                     1.0 / slope);
        for (std::size_t i = 0; i < sizes.size(); ++i)
          std::fprintf(f, "%s%.0f", i ? ", " : "", sizes[i]);
        std::fprintf(f, "],\n \"one_way_s\": [");
        for (std::size_t i = 0; i < times.size(); ++i)
          std::fprintf(f, "%s%.6e", i ? ", " : "", times[i]);
        std::fprintf(f, "]\n}\n");
        std::fclose(f);
      }
    }
  }
  MPI_Finalize();
  return 0;
}
