// coloc/core/run_config.hpp — the case-file keys that belong to no single physics:
// the case name, the run control (mode, steps, end time, time steps) and the output folder.
#pragma once

#include "coloc/core/config.hpp"

namespace coloc {

/// name, description, gravity, run.{mode,steps,end_time,progress_interval_s}.
void declareRunConfig(Schema& s);

/// What the run advances: both physics, one of them, or the paper's DummyDEM.
enum class RunMode { Coupled, FluidOnly, ParticlesOnly, DummyDem };
RunMode runMode(const Config& cfg);
const char* runModeName(RunMode m);

}  // namespace coloc
