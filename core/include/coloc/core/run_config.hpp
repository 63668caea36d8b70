// coloc/core/run_config.hpp — the case-file keys that belong to no single physics:
// the case name, the run control (mode, steps, end time, time steps) and the output folder.
#pragma once

#include "coloc/core/config.hpp"

namespace coloc {

/// name, description, gravity, run.{mode,steps,end_time,progress_interval_s,progress_columns}.
void declareRunConfig(Schema& s);

/// The names run.progress_columns accepts, in the order of the driver's column table
/// (bench/driver/progress.cpp; docs/output.md).
const std::vector<std::string>& progressColumnNames();

/// What the run advances: both physics, one of them, or the paper's DummyDEM.
enum class RunMode { Coupled, FluidOnly, ParticlesOnly, DummyDem };
RunMode runMode(const Config& cfg);
const char* runModeName(RunMode m);

}  // namespace coloc
