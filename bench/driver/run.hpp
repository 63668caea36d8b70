// The `coloc run` job: read the case, build the decomposition and the physics, run the steps,
// write the report.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "snapshot.hpp"

namespace coloc {

struct RunOptions {
  std::string casePath;
  std::vector<std::string> overrides;
  std::string outDir;
  bool quiet = false;
  std::string restart;      // --restart FILE: continue from this checkpoint
  bool overwrite = false;   // --overwrite: remove an earlier run's files in the folders first
  std::string commandLine;  // as given (report.json provenance.command_line)
};

// Exit status of `coloc run`, the same on every rank (docs/robustness.md):
/// Bad input: the case file, the command line, a --restart file, a set-up the ranks cannot take.
inline constexpr int kInputErrorStatus = 2;
/// The run failed inside the time loop (blow-up: NaN, CFL, DEM checks), or an internal error.
inline constexpr int kRunFailedStatus = 3;
/// A file or folder could not be written (full disk, permissions, read-only, size limit).
inline constexpr int kIoErrorStatus = 4;
/// Stopped by SIGINT or SIGTERM after the final checkpoint and report: 128 + the signal
/// (130 for SIGINT, 143 for SIGTERM).
inline constexpr int kInterruptedBase = 128;

/// Returns the process exit status (above). Every failure is agreed by every rank at the end of
/// the phase it happened in and printed once by rank 0; DIR/report.json then says how the run
/// ended. Throws coloc::Error (on every rank) for an input error found before the output folder
/// is known (the case file or the command line).
/// A run that ends well and asks for a picture (output.snapshot) sets `snapshot` on rank 0:
/// main() draws it after MPI_Finalize (snapshot.hpp).
int runCase(const Comm& world, const RunOptions& opts, std::optional<SnapshotJob>& snapshot);
/// A library stopped the job with MPI_Abort(-1) (hypre does when an allocation fails): called by
/// the driver's MPI_Abort (main.cpp) on the rank that called it. Prints the error, writes
/// report.json ("failed", out_of_memory) from this rank alone when a run's output folder is known,
/// and ends every rank with kRunFailedStatus. Does not return.
[[noreturn]] void libraryAborted();

/// The schema of the whole case file, described for `coloc keys`.
std::string describeKeys();

}  // namespace coloc
