// output.snapshot and `coloc snapshot`: a picture of a run's last output, OUT/snapshot.png, drawn
// by bench/scripts/snapshot.py (docs/output.md, "Snapshot").
//
// The script runs in a child process that main() starts after MPI_Finalize (main.cpp says why),
// through posix_spawn (no shell, no fork of the whole address space).
#pragma once

#include <optional>
#include <string>

#include "coloc/core/config.hpp"

namespace CLI {
class App;
}

namespace coloc {

/// One drawing of snapshot.py: `snapshot.py DATA_DIR [--step N] [--png PNG] [--report REPORT]
/// [--full]`, what it prints going to the terminal (unless `quiet`) and to `logPath` (when set).
struct SnapshotJob {
  std::string dataDir;  // the folder of fields_NNNNNN.h5 (output.dir)
  std::string png;      // empty: DATA_DIR/snapshot.png
  std::string report;   // empty: DATA_DIR/report.json
  long long step = -1;  // -1: the last output step
  bool full = false;    // the whole box (no crop above the bed)
  bool quiet = false;   // the script's lines to the log only
  std::string logPath;  // the run's log (OUT/log.txt), appended to; empty: none
  /// The picture at the end of a `coloc run`: a failure is a warning and leaves the run's exit
  /// status alone. Otherwise (`coloc snapshot`) the script's exit status is the command's.
  bool ofRun = false;
};

/// output.snapshot: the picture a run that ended well asks for (output.snapshot, fields written
/// at an interval > 0): OUT/snapshot.png of output.dir's last output, the log OUT/log.txt;
/// nothing otherwise.
std::optional<SnapshotJob> snapshotDue(const Config& cfg, const std::string& outDir, bool quiet);

/// Runs snapshot.py on `job` and waits for it. Returns the exit status for the process: 0 for a
/// run's picture (a failure is printed as a warning, the run's output is complete), the script's
/// exit status (1 when it cannot be started) for `coloc snapshot`. Starts a child process: call it
/// after MPI_Finalize, never from a live MPI process.
int drawSnapshot(const SnapshotJob& job);

/// `coloc snapshot OUT_DIR [--png FILE] [--full] [--step N]`: adds the subcommand to `app`,
/// its options parsed into `job`.
CLI::App* addSnapshotCommand(CLI::App& app, SnapshotJob& job);

/// `coloc snapshot ...` without MPI (main() calls it before MPI_Init): parses argv, draws.
/// Returns the exit status (2 for a bad command line).
int snapshotCommand(int argc, char** argv);

}  // namespace coloc
