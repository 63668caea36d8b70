// output.snapshot: a picture of a run's last output, OUT/snapshot.png, drawn by
// bench/scripts/snapshot.py (docs/output.md, "Snapshot").
#pragma once

#include <string>

#include "coloc/core/config.hpp"
#include "run_log.hpp"

namespace coloc {

/// output.snapshot: rank 0 runs bench/scripts/snapshot.py on the run's output (a picture of the
/// last fields and particles, OUT/snapshot.png). Only a warning when it cannot.
void drawSnapshot(const Config& cfg, const std::string& outDir, bool quiet, RunLog& log);

}  // namespace coloc
