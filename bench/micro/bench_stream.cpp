// bench_stream: memory-bandwidth contention on one node, the memory term of
// bench/scripts/model.py. STREAM triad a[i] = b[i] + s * c[i] (24 bytes an element, the STREAM
// convention) on each rank's own arrays; for k = 1 .. size ranks streaming at once (the others
// wait at the barrier) it measures the bandwidth ONE rank gets, best of --trials clean trials
// (every streaming rank on its CPU all the trial long: thread CPU time >= 95 % of wall; at most
// --seconds a point), at each per-rank working set --mib (the three arrays, MiB; repeat the flag;
// default 3, 12 and 48: in L2+L3, half the L3, and two ranks together 3x the 32 MiB L3 here).
// contention(k) = B(1) / B(k); model.py takes the size where two ranks contend most.
//   mpirun -n 2 build/bench/bench_stream --json bench/results/model/stream.json
// --co-run SECONDS: one process streams (the largest --mib) for SECONDS and exits: the
// co-runner of the memory-share calibration (bench/scripts/validate_model.py).
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "proc_load.hpp"

namespace {

double triad(std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& c,
             int passes) {
  const std::size_t n = a.size();
  const double s = 1.0000001;
  for (int p = 0; p < passes; ++p)
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
  return a[n / 2];
}

double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::string json;
  std::vector<double> mib;
  int trials = 10;
  double coRun = 0, maxSeconds = 2.0;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) json = argv[i + 1];
    if (std::strcmp(argv[i], "--mib") == 0) mib.push_back(std::atof(argv[i + 1]));
    if (std::strcmp(argv[i], "--trials") == 0) trials = std::max(1, std::atoi(argv[i + 1]));
    if (std::strcmp(argv[i], "--co-run") == 0) coRun = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--seconds") == 0) maxSeconds = std::atof(argv[i + 1]);
  }
  if (mib.empty()) mib = {3.0, 12.0, 48.0};
  std::sort(mib.begin(), mib.end());
  volatile double sink = 0;
  if (coRun > 0) {
    const std::size_t n = static_cast<std::size_t>(mib.back() * 1048576.0 / 24.0);
    std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
    const double t0 = MPI_Wtime();
    while (MPI_Wtime() - t0 < coRun) sink = sink + triad(a, b, c, 1);
    MPI_Finalize();
    return 0;
  }
  // perRank[s][k-1]: bytes/s one rank gets at size s with k ranks streaming.
  std::vector<std::vector<double>> perRank(mib.size(), std::vector<double>(size, 0.0));
  std::vector<std::vector<int>> validTrials(mib.size(), std::vector<int>(size, 0));
  for (std::size_t si = 0; si < mib.size(); ++si) {
    const std::size_t n = static_cast<std::size_t>(mib[si] * 1048576.0 / 24.0);
    std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
    // ~5 ms a trial (50 MB at ~10 GB/s): short enough to fit between two preemptions on a
    // shared machine. A trial counts only where every streaming rank was on its CPU for all of
    // it (thread CPU time >= 95 % of wall): then k ranks really streamed at once.
    const int passes = std::max(1, static_cast<int>(5.0e7 / (24.0 * static_cast<double>(n))));
    sink = sink + triad(a, b, c, 1);  // first touch
    for (int k = 1; k <= size; ++k) {
      double best = 1e300, bestAny = 1e300;
      int valid = 0;
      const double tStart = MPI_Wtime();
      // at most --seconds (default 2) a point: the clock of rank 0 decides for all
      for (int stop = 0; !stop && valid < trials;) {
        MPI_Barrier(MPI_COMM_WORLD);
        const double t0 = MPI_Wtime(), c0 = cpuSeconds();
        if (rank < k) sink = sink + triad(a, b, c, passes);
        double dt = rank < k ? MPI_Wtime() - t0 : 0.0;
        double on = rank < k ? (cpuSeconds() - c0) / std::max(dt, 1e-12) : 1.0;
        double slowest = 0, leastOn = 0;
        // the slowest streaming rank: a rank descheduled for part of the trial lets the others
        // run alone and look faster; its own time is longer, so the max stays honest.
        MPI_Allreduce(&dt, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        MPI_Allreduce(&on, &leastOn, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
        bestAny = std::min(bestAny, slowest);
        stop = rank == 0 && MPI_Wtime() - tStart > maxSeconds;
        MPI_Bcast(&stop, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (leastOn >= 0.95) {
          ++valid;
          best = std::min(best, slowest);
        }
      }
      if (valid == 0) best = bestAny;  // flagged in the output: no clean trial
      perRank[si][k - 1] = 24.0 * static_cast<double>(n) * passes / best;
      validTrials[si][k - 1] = valid;
    }
  }
  if (rank == 0) {
    std::printf("%10s %8s %16s %16s %12s %8s\n", "MiB/rank", "ranks", "GB/s one rank", "GB/s node",
                "contention", "clean");
    for (std::size_t si = 0; si < mib.size(); ++si)
      for (int k = 1; k <= size; ++k)
        std::printf("%10.1f %8d %16.3f %16.3f %12.3f %8d\n", mib[si], k, perRank[si][k - 1] / 1e9,
                    k * perRank[si][k - 1] / 1e9, perRank[si][0] / perRank[si][k - 1],
                    validTrials[si][k - 1]);
    std::printf("load: %s\n", coloc::bench::loadavg().c_str());
    if (!json.empty()) {
      if (FILE* f = std::fopen(json.c_str(), "w")) {
        std::fprintf(f, "{\n \"kernel\": \"triad, 24 B an element\",\n \"loadavg\": \"%s\",\n",
                     coloc::bench::loadavg().c_str());
        std::fprintf(f, " \"ranks\": %d,\n \"sizes_mib\": [", size);
        for (std::size_t si = 0; si < mib.size(); ++si)
          std::fprintf(f, "%s%.1f", si ? ", " : "", mib[si]);
        std::fprintf(f, "],\n \"per_rank_Bps\": [");
        for (std::size_t si = 0; si < mib.size(); ++si) {
          std::fprintf(f, "%s[", si ? ", " : "");
          for (int k = 1; k <= size; ++k)
            std::fprintf(f, "%s%.6e", k > 1 ? ", " : "", perRank[si][k - 1]);
          std::fprintf(f, "]");
        }
        std::fprintf(f, "],\n \"clean_trials\": [");
        for (std::size_t si = 0; si < mib.size(); ++si) {
          std::fprintf(f, "%s[", si ? ", " : "");
          for (int k = 1; k <= size; ++k)
            std::fprintf(f, "%s%d", k > 1 ? ", " : "", validTrials[si][k - 1]);
          std::fprintf(f, "]");
        }
        std::fprintf(f, "]\n}\n");
        std::fclose(f);
      }
    }
  }
  MPI_Finalize();
  return sink == 12345.678 ? 1 : 0;
}
