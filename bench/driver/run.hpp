// The `coloc run` job: read the case, build the decomposition and the physics, run the steps,
// write the report.
#pragma once

#include <string>
#include <vector>

#include "coloc/core/comm.hpp"

namespace coloc {

inline constexpr const char* kVersionString = "coloc 0.1.0";

struct RunOptions {
  std::string casePath;
  std::vector<std::string> overrides;
  std::string outDir;
  bool quiet = false;
  std::string restart;  // --restart FILE: continue from this checkpoint
};

/// Exit status of a run that failed inside the time loop (blow-up: NaN, CFL, DEM checks).
inline constexpr int kRunFailedStatus = 3;

/// Returns the process exit status (0, or kRunFailedStatus when the time loop failed: the message
/// is printed on rank 0 and the state at the failure written as a checkpoint marked failed);
/// throws coloc::Error (on every rank) for bad input, including a bad --restart file.
int runCase(const Comm& world, const RunOptions& opts);
/// The schema of the whole case file, described for `coloc keys`.
std::string describeKeys();

}  // namespace coloc
