// SIGTERM/SIGINT during `coloc run`: the run stops after the current step with a checkpoint and a
// report marked interrupted (docs/robustness.md); a second signal ends the process at once.
#pragma once

namespace coloc {

/// SIGTERM/SIGINT ask the run to stop after the current step (a second one exits at once);
/// SIGXFSZ is ignored (a file-size limit is an I/O error). Called by main() for `coloc run`.
void installStopSignals();

/// The stop signal received so far (0: none); read by each phase's agreement (run.cpp).
int stopSignal();

/// "SIGTERM", "SIGINT" or "a signal" (report.json `signal`, the messages).
const char* signalName(int sig);

}  // namespace coloc
