// The failure-injection hook of the test build of the driver (target coloc_faults: the `coloc`
// sources plus this file; the `coloc` binary has no hook and reads no variable for it).
//
//   COLOC_FAULT=POINT:RANK:STEP:KIND   at fault point POINT (coloc/core/fault.hpp: outdir, setup,
//       restart, fluid, dem, coupling, output, series, checkpoint, report), on world rank RANK
//       (or "all"), the first time that point is reached at step STEP, do KIND:
//         error      throw coloc::Error on that rank only (the others do not know)
//         io         throw coloc::IoError ("No space left on device", injected)
//         exception  throw std::runtime_error (an unexpected exception)
//         kill       SIGKILL itself
//         signal     SIGTERM itself (a stop request, as from a batch system)
//         signal2    SIGTERM itself twice (the second exits at once)
//         bad_alloc  throw std::bad_alloc (an allocation that failed in coloc's own code)
//         abort      MPI_Abort(MPI_COMM_WORLD, -1), as hypre does when its allocation fails
//   COLOC_TEST_KILL_IN_CHECKPOINT=N    the same as checkpoint:all:N:kill (tests of issue 8).
#include <mpi.h>

#include <csignal>
#include <cstdlib>
#include <new>
#include <stdexcept>
#include <string>

#include "coloc/core/error.hpp"
#include "coloc/core/fault.hpp"

namespace {

struct Fault {
  std::string point, kind;
  int rank = -1;  // -1: every rank
  long long step = 0;
  bool fired = false;
};

Fault& fault() {
  static Fault f;
  return f;
}

void hook(const char* point, long long step) {
  Fault& f = fault();
  if (f.fired || f.point != point || f.step != step) return;
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (f.rank >= 0 && f.rank != rank) return;
  f.fired = true;
  const std::string what = std::string("injected fault at ") + point + ", step " +
                           std::to_string(step) + ", rank " + std::to_string(rank);
  if (f.kind == "error") throw coloc::Error(what);
  if (f.kind == "io") throw coloc::IoError(what + ": No space left on device");
  if (f.kind == "exception") throw std::runtime_error(what);
  if (f.kind == "bad_alloc") throw std::bad_alloc();
  if (f.kind == "abort") MPI_Abort(MPI_COMM_WORLD, -1);
  if (f.kind == "kill") std::raise(SIGKILL);
  if (f.kind == "signal") std::raise(SIGTERM);
  if (f.kind == "signal2") {
    std::raise(SIGTERM);
    std::raise(SIGTERM);
  }
}

bool installFromEnvironment() {
  Fault& f = fault();
  if (const char* k = std::getenv("COLOC_TEST_KILL_IN_CHECKPOINT")) {
    f.point = "checkpoint";
    f.kind = "kill";
    f.step = std::atoll(k);
    coloc::fault::install(hook);
  }
  if (const char* spec = std::getenv("COLOC_FAULT")) {
    const std::string s = spec;
    const auto a = s.find(':'), b = s.find(':', a + 1), c = s.find(':', b + 1);
    if (a == std::string::npos || b == std::string::npos || c == std::string::npos) return false;
    f.point = s.substr(0, a);
    const std::string rank = s.substr(a + 1, b - a - 1);
    f.rank = rank == "all" ? -1 : std::atoi(rank.c_str());
    f.step = std::atoll(s.substr(b + 1, c - b - 1).c_str());
    f.kind = s.substr(c + 1);
    coloc::fault::install(hook);
  }
  return true;
}

[[maybe_unused]] const bool installed = installFromEnvironment();

}  // namespace
