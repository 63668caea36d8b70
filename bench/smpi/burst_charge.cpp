// bench/smpi/burst_charge.cpp — what SMPI charges a simulated rank for a compute burst, less the
// cost of timing it (docs/smpi.md, "The charge of an empty burst").
//
// SMPI times each burst of a rank (its code between two MPI calls) with the thread's CPU clock
// and charges it to the simulated core. The interval it times also holds its own work: the end
// of one MPI call after the clock starts, the start of the next before it stops, and one read of
// the clock itself (clock_gettime(CLOCK_THREAD_CPUTIME_ID) is a system call: 1.3 us a read on the
// development VM). An empty burst, which costs a real rank nothing, is charged ~2 us here; hypre
// makes thousands of MPI calls a step a rank, so that charge, not its work, is most of its
// simulated set-up above a few dozen ranks.
//
// This library is preloaded into smpirun's process by bench/scripts/smpi_run.py (LD_PRELOAD). It
// replaces the one function of SimGrid 3.32 through which every timed burst passes,
// xbt_os_timer_elapsed (called by smpi_bench_end through the PLT), by the real one less
//   COLOC_SMPI_BURST_OFFSET  seconds, never below 0 (unset or 0: SMPI's own charge, unchanged);
// the offset is the median charge of an empty burst, measured just before by running
// smpi_empty_bursts with
//   COLOC_SMPI_BURST_STATS=FILE  which writes the number of bursts and their median, 10th and
//                                90th percentiles (seconds, as SMPI timed them) at exit;
//   COLOC_SMPI_BURST_TOTALS=FILE appends at exit the bursts timed, their raw and charged sums,
//                                and the count and charged sum of those under 1 us, 1-10 us,
//                                10-100 us and longer (the last also holds SimGrid's own uses of
//                                the timer: not simulated time;
//                                bench/results/smpi/poll-sensitivity).
// Other users of the function (SimGrid's own timers) are not simulated time.
#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace {

using Elapsed = double (*)(const void*);

constexpr int kBins = 20000;        // the statistics: 10 ns bins up to 200 us
constexpr double kBinWidth = 1e-8;  // seconds
long histogram[kBins + 1];          // the last bin: longer bursts
long bursts = 0;

Elapsed realElapsed() {
  static const Elapsed fn = reinterpret_cast<Elapsed>(dlsym(RTLD_NEXT, "xbt_os_timer_elapsed"));
  if (!fn) {
    std::fprintf(stderr, "burst_charge: xbt_os_timer_elapsed not found (not SimGrid 3.32?)\n");
    std::abort();
  }
  return fn;
}

double offset() {
  static const double s = [] {
    const char* v = std::getenv("COLOC_SMPI_BURST_OFFSET");
    return v ? std::atof(v) : 0.0;
  }();
  return s;
}

/// COLOC_SMPI_BURST_TOTALS: what the run's bursts were charged, by size.
struct Totals {
  long n = 0;
  double raw = 0, charged = 0;
  long count[4] = {};
  double chargedBySize[4] = {};
};
Totals totals;

const char* totalsPath() {
  static const char* path = std::getenv("COLOC_SMPI_BURST_TOTALS");
  return path;
}

bool recording() {
  static const bool on = std::getenv("COLOC_SMPI_BURST_STATS") != nullptr;
  return on;
}

double quantile(double q) {
  const long want = static_cast<long>(q * static_cast<double>(bursts));
  long seen = 0;
  for (int b = 0; b <= kBins; ++b) {
    seen += histogram[b];
    if (seen > want) return (b + 0.5) * kBinWidth;
  }
  return kBins * kBinWidth;
}

__attribute__((destructor)) void writeStats() {
  const char* path = std::getenv("COLOC_SMPI_BURST_STATS");
  if (!path || bursts == 0) return;  // not asked, or a process of smpirun that ran no rank
  if (std::FILE* f = std::fopen(path, "w")) {
    std::fprintf(f, "{\"bursts\": %ld, \"median_s\": %.4e, \"p10_s\": %.4e, \"p90_s\": %.4e}\n",
                 bursts, quantile(0.5), quantile(0.1), quantile(0.9));
    std::fclose(f);
  }
}

__attribute__((destructor)) void writeTotals() {
  const char* path = totalsPath();
  if (!path || totals.n == 0) return;
  if (std::FILE* f = std::fopen(path, "a")) {
    const Totals& t = totals;
    std::fprintf(f,
                 "{\"bursts\": %ld, \"raw_s\": %.6e, \"charged_s\": %.6e, \"by_size\": [[%ld, "
                 "%.6e], [%ld, %.6e], [%ld, %.6e], [%ld, %.6e]]}\n",
                 t.n, t.raw, t.charged, t.count[0], t.chargedBySize[0], t.count[1],
                 t.chargedBySize[1], t.count[2], t.chargedBySize[2], t.count[3],
                 t.chargedBySize[3]);
    std::fclose(f);
  }
}

}  // namespace

extern "C" double xbt_os_timer_elapsed(const void* timer) {
  const double t = realElapsed()(timer);
  if (recording()) {
    const long b = static_cast<long>(t / kBinWidth);
    ++histogram[b < 0 ? 0 : (b > kBins ? kBins : b)];
    ++bursts;
  }
  const double charged = std::max(t - offset(), 0.0);
  if (totalsPath()) {
    const int k = t < 1e-6 ? 0 : (t < 1e-5 ? 1 : (t < 1e-4 ? 2 : 3));
    ++totals.n;
    totals.raw += t;
    totals.charged += charged;
    ++totals.count[k];
    totals.chargedBySize[k] += charged;
  }
  return charged;
}
