// bench_noise: how unevenly the cores of this machine run the same work, the noise term of
// bench/scripts/model.py. A perfectly balanced coupled step still waits at its barriers when one
// core runs slower than another for a while (a shared host, frequency changes, the hypervisor
// taking a core: "steal"); no work model predicts that, so it is measured here.
//
// Every rank repeats the same fixed piece of work (a DEM-like pair loop on a cache-resident set
// of points, then a triad pass over --mib of its own memory) and then waits at a barrier,
// --intervals times; rank 0 sizes the work once so that an interval takes about --interval-ms.
// For k = 2 .. size ranks working at once (the others wait at the barrier) and interval i, t_ri
// is rank r's work time. Reported for each k:
//   wait_fraction = sum_i (max_r t_ri - mean_r t_ri) / sum_i max_r t_ri
//     the share of a balanced step spent waiting for the slowest rank (what model.py adds);
//   noise = sum_i (max_r t_ri - mean_r t_ri) / sum_i mean_r t_ri
//     the same as a fraction of the mean work (model.py's eta(k));
// and, at k = size, the quantiles of s_ri = t_ri / median(t) pooled over ranks and intervals
// (model.py extrapolates eta beyond the measured ranks from them, as independent draws), each
// rank's mean speed and the steal time of its CPU during the run (/proc/stat).
//   mpirun -n 2 build/bench/bench_noise --json bench/results/model/noise.json
#include <mpi.h>
#include <sched.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "proc_load.hpp"

namespace {

struct Work {
  std::vector<double> x, y, z, f;  // points of the pair loop (L1/L2)
  std::vector<double> a, b, c;     // the triad's arrays
};

// One repetition: every pair of points closer than the cut-off gets a Hertz-like force
// (sqrt, a division: the arithmetic of the DEM's contact loop), then one triad pass.
double kernel(Work& w, long long reps) {
  const std::size_t n = w.x.size();  // 0: no pair loop (--kernel triad)
  double acc = 0.0;
  for (long long r = 0; r < reps; ++r) {
    for (std::size_t i = 0; i < n; ++i) {
      double fi = 0.0;
      for (std::size_t j = i + 1; j < std::min(n, i + 24); ++j) {
        const double dx = w.x[i] - w.x[j], dy = w.y[i] - w.y[j], dz = w.z[i] - w.z[j];
        const double d2 = dx * dx + dy * dy + dz * dz;
        const double d = std::sqrt(d2 + 1e-12);
        const double ov = 1.0 - d;
        fi += ov > 0.0 ? ov * std::sqrt(ov) / d : 0.0;
      }
      w.f[i] += fi;
    }
    const std::size_t m = w.a.size();
    for (std::size_t i = 0; i < m; ++i) w.a[i] = w.b[i] + 1.0000001 * w.c[i];
    acc += (n ? w.f[n / 2] : 0.0) + w.a[m / 2];
  }
  return acc;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Steal jiffies of one CPU (/proc/stat's 8th value), -1 where not readable.
long long stealOf(int cpu) {
  std::ifstream f("/proc/stat");
  std::string line, want = "cpu" + std::to_string(cpu);
  while (std::getline(f, line)) {
    std::istringstream s(line);
    std::string name;
    s >> name;
    if (name != want) continue;
    long long v[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (auto& x : v) s >> x;
    return v[7];
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::string json;
  int intervals = 400;
  double intervalMs = 2.0, mib = 1.0;
  std::string kind = "both";
  for (int i = 1; i < argc; ++i) {
    const bool val = i + 1 < argc;
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      if (rank == 0)
        std::printf(
            "bench_noise: the spread of the cores' speed on the same work (model.py's noise)\n"
            "  --intervals N     intervals of work + barrier for each rank count (400)\n"
            "  --interval-ms T   work of one interval, milliseconds (2)\n"
            "  --mib M           working set of the triad a rank, MiB (1)\n"
            "  --kernel K        pairs (compute), triad (memory) or both (default)\n"
            "  --json FILE       write the figures as JSON\n");
      MPI_Finalize();
      return 0;
    }
    if (!val) continue;
    if (std::strcmp(argv[i], "--json") == 0) json = argv[i + 1];
    if (std::strcmp(argv[i], "--intervals") == 0) intervals = std::max(4, std::atoi(argv[i + 1]));
    if (std::strcmp(argv[i], "--interval-ms") == 0) intervalMs = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--mib") == 0) mib = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--kernel") == 0) kind = argv[i + 1];
  }
  if (kind != "pairs" && kind != "triad" && kind != "both") {
    if (rank == 0)
      std::fprintf(stderr, "bench_noise: --kernel %s: pairs, triad or both\n", kind.c_str());
    MPI_Finalize();
    return 2;
  }
  Work w;
  const std::size_t np = kind == "triad" ? 0 : 4096;
  for (std::size_t i = 0; i < np; ++i) {  // a jittered line of points 0.9 apart: ~2 contacts
    const double s = static_cast<double>(i);
    w.x.push_back(0.9 * s + 0.01 * std::sin(s));
    w.y.push_back(0.01 * std::cos(s));
    w.z.push_back(0.0);
  }
  w.f.assign(np, 0.0);
  const std::size_t m =
      kind == "pairs" ? 1
                      : std::max<std::size_t>(1, static_cast<std::size_t>(mib * 1048576.0 / 24.0));
  w.a.assign(m, 0.0);
  w.b.assign(m, 1.0);
  w.c.assign(m, 2.0);
  volatile double sink = 0;
  // Size the work on rank 0 (best of 5 after a warm-up) and give every rank the same count.
  long long reps = 1;
  if (rank == 0) {
    sink = sink + kernel(w, 2);
    double best = 1e30;
    for (int t = 0; t < 5; ++t) {
      const double t0 = MPI_Wtime();
      sink = sink + kernel(w, 4);
      best = std::min(best, (MPI_Wtime() - t0) / 4.0);
    }
    reps = std::max<long long>(1, std::llround(intervalMs * 1e-3 / best));
  }
  MPI_Bcast(&reps, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  const int cpu = sched_getcpu();
  const long long steal0 = stealOf(cpu);
  const double wall0 = MPI_Wtime();
  // times[k][r * intervals + i]: rank r's work in interval i with k ranks working (r < k).
  std::vector<std::vector<double>> times(size + 1);
  for (int k = std::min(2, size); k <= size; ++k) {
    std::vector<double> mine(intervals, 0.0);
    MPI_Barrier(MPI_COMM_WORLD);
    for (int i = 0; i < intervals; ++i) {
      if (rank < k) {
        const double t0 = MPI_Wtime();
        sink = sink + kernel(w, reps);
        mine[i] = MPI_Wtime() - t0;
      }
      MPI_Barrier(MPI_COMM_WORLD);
    }
    times[k].assign(static_cast<std::size_t>(intervals) * size, 0.0);
    MPI_Gather(mine.data(), intervals, MPI_DOUBLE, times[k].data(), intervals, MPI_DOUBLE, 0,
               MPI_COMM_WORLD);
  }
  const double wall = MPI_Wtime() - wall0;
  const long long steal1 = stealOf(cpu);
  long long mySteal[2] = {cpu, steal0 >= 0 && steal1 >= 0 ? steal1 - steal0 : -1};
  std::vector<long long> steals(2 * static_cast<std::size_t>(size));
  MPI_Gather(mySteal, 2, MPI_LONG_LONG, steals.data(), 2, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  if (rank == 0) {
    std::ostringstream js;
    js << "{\n \"benchmark\": \"bench_noise\",\n \"ranks\": " << size
       << ",\n \"intervals\": " << intervals << ",\n \"interval_ms\": " << intervalMs
       << ",\n \"kernel\": \"" << kind << "\",\n \"mib\": " << (kind == "pairs" ? 0.0 : mib)
       << ",\n \"wall_s\": " << wall << ",\n \"loadavg\": \"" << coloc::bench::loadavg()
       << "\",\n \"by_ranks\": [";
    std::printf(
        "bench_noise: %d ranks, %d intervals of %.2f ms (kernel %s, triad %.2f MiB), "
        "%.1f s\n",
        size, intervals, intervalMs, kind.c_str(), kind == "pairs" ? 0.0 : mib, wall);
    std::printf("%6s %14s %10s %14s\n", "ranks", "wait_fraction", "noise", "mean_work_ms");
    bool first = true;
    for (int k = std::min(2, size); k <= size; ++k) {
      double sumWait = 0, sumMax = 0, sumMean = 0;
      for (int i = 0; i < intervals; ++i) {
        double mx = 0, mean = 0;
        for (int r = 0; r < k; ++r) {
          const double t = times[k][r * intervals + i];
          mx = std::max(mx, t);
          mean += t / k;
        }
        sumWait += mx - mean;
        sumMax += mx;
        sumMean += mean;
      }
      const double wf = sumMax > 0 ? sumWait / sumMax : 0,
                   eta = sumMean > 0 ? sumWait / sumMean : 0;
      std::printf("%6d %14.4f %10.4f %14.3f\n", k, wf, eta, 1e3 * sumMean / intervals);
      js << (first ? "" : ",") << "\n  {\"ranks\": " << k << ", \"wait_fraction\": " << wf
         << ", \"noise\": " << eta << ", \"mean_work_s\": " << sumMean / intervals << "}";
      first = false;
    }
    js << "\n ]";
    // Pooled relative times at k = size, and each rank's mean.
    const std::vector<double>& t = times[size];
    const double med = median(t);
    std::vector<double> s(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) s[i] = med > 0 ? t[i] / med : 1.0;
    std::sort(s.begin(), s.end());
    js << ",\n \"relative_time_quantiles\": [";
    const int nq = 100;
    for (int q = 0; q <= nq; ++q) {
      const std::size_t at = std::min(
          s.size() - 1, static_cast<std::size_t>(std::llround(q / double(nq) * (s.size() - 1))));
      js << (q ? ", " : "") << s[at];
    }
    js << "],\n \"per_rank\": [";
    for (int r = 0; r < size; ++r) {
      double sum = 0;
      for (int i = 0; i < intervals; ++i) sum += t[r * intervals + i];
      js << (r ? ", " : "") << "{\"rank\": " << r << ", \"cpu\": " << steals[2 * r]
         << ", \"mean_work_s\": " << sum / intervals << ", \"steal_jiffies\": " << steals[2 * r + 1]
         << "}";
      std::printf("rank %d on cpu %lld: mean work %.3f ms, steal %lld jiffies\n", r, steals[2 * r],
                  1e3 * sum / intervals, steals[2 * r + 1]);
    }
    js << "]\n}\n";
    if (!json.empty()) {
      const std::string tmp = json + ".tmp";
      std::ofstream f(tmp);
      f << js.str();
      f.close();
      if (!f || std::rename(tmp.c_str(), json.c_str()) != 0) {
        std::fprintf(stderr, "bench_noise: cannot write %s\n", json.c_str());
        MPI_Abort(MPI_COMM_WORLD, 1);
      }
    }
  }
  MPI_Finalize();
  return sink == 12345.678 ? 1 : 0;
}
