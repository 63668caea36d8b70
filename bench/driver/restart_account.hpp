// What a restart keeps from its checkpoint and what it takes from the case, and the refusal of a
// restart with nothing to run (docs/robustness.md, "Restarts: what comes from where").
#pragma once

#include <string>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"
#include "run_log.hpp"

namespace coloc {

/// The keys whose values differ between the checkpoint's stored case and `cfg`, split into those
/// the restart keeps from the checkpoint (what is baked into its state: the particle sources and
/// seed, the materials' densities, the fluid's initial velocity) and those it takes from the
/// case: report.json's `restart` object ({checkpoint, step, time, kept_from_checkpoint,
/// taken_from_case}); rank 0 prints them as notes (through `log`). Collective (reads the file's
/// attributes).
Json accountRestart(const Comm& world, const std::string& checkpoint, const Config& cfg,
                    RunLog& log);

/// ConfigError naming run.steps (or run.end_time) when a run restarted at `steps`, `time` has
/// nothing left to run.
void refuseEmptyRestart(const Config& cfg, const std::string& checkpoint, long long steps,
                        double time);

}  // namespace coloc
