// The end of a `coloc run`: the table of phases (min / avg / max over ranks and the share of the
// time loop, as LAMMPS prints its "MPI task timing breakdown") and the figure of merit, both from
// the run's report (report.json), so that they say exactly what it says.
#pragma once

#include <string>
#include <vector>

#include "coloc/core/config.hpp"

namespace coloc {

/// The lines of the phase table of `report` (its timers, run.wall_s): one row per phase of the
/// time loop that ran (calls > 0), "phases" (their sum), "other" (the loop's wall time in no
/// phase) and "loop" (run.wall_s), then the set-up. Numbers as %.6g, percentages as %.2f.
std::vector<std::string> phaseTable(const Json& report);

/// report.json's "figure_of_merit": particle-steps and cell-steps a second and a core
/// (throughput over provenance.cores_used), the inter-physics share of the step
/// (fractions.inter_physics) and the cores counted.
Json figureOfMerit(const Json& report);

/// The one line the run prints of it.
std::string figureOfMeritLine(const Json& figureOfMerit);

}  // namespace coloc
