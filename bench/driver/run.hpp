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
};

/// Returns the process exit status; throws coloc::Error (on every rank) for bad input.
int runCase(const Comm& world, const RunOptions& opts);
/// The schema of the whole case file, described for `coloc keys`.
std::string describeKeys();

}  // namespace coloc
