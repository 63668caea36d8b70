// SIGTERM/SIGINT during `coloc run` (stop_signals.hpp).
#include "stop_signals.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdlib>

#include "run.hpp"

namespace coloc {
namespace {

/// The stop signal received so far (0: none); set by the handler installStopSignals() puts in.
volatile std::sig_atomic_t received = 0;

extern "C" void onStopSignal(int sig) {
  if (received != 0) {  // the second: at once (async-signal-safe calls only)
    static const char msg[] = "coloc: second stop signal: exiting now, without a checkpoint\n";
    const ssize_t n = ::write(2, msg, sizeof msg - 1);
    (void)n;
    std::_Exit(kInterruptedBase + sig);
  }
  received = sig;
}

}  // namespace

void installStopSignals() {
  struct sigaction a {};
  a.sa_handler = onStopSignal;
  sigemptyset(&a.sa_mask);
  a.sa_flags = SA_RESTART;
  sigaction(SIGTERM, &a, nullptr);
  sigaction(SIGINT, &a, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);  // a write past RLIMIT_FSIZE fails with EFBIG: an I/O error
  // A terminal that went away (`coloc run ... | head -1`) is no reason to end the run without
  // its report: the lines to it fail (EPIPE) and the run goes on, its log and report complete.
  std::signal(SIGPIPE, SIG_IGN);
}

int stopSignal() {
  return static_cast<int>(received);
}

const char* signalName(int sig) {
  switch (sig) {
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    default:
      return "a signal";
  }
}

}  // namespace coloc
