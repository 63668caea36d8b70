#include "coloc/core/run_config.hpp"

namespace coloc {

void declareRunConfig(Schema& s) {
  s.string("name", "case", "case name (default output folder out/<name>)");
  s.string("description", "", "free text, copied to the report");
  s.string("run.mode", "coupled",
           "what runs: coupled, fluid (CFD only), particles (DEM only), "
           "dummy_dem (paper's case 2: particles frozen, every exchange done)",
           {"coupled", "fluid", "particles", "dummy_dem"});
  s.vec3("gravity", std::array<double, 3>{0, 0, 0},
         "gravitational acceleration (m/s^2), felt by the particles and the fluid");
  s.integer("run.steps", 10,
            "number of steps: CFD steps (fluid), coupling steps (coupled, dummy_dem), groups of "
            "max(1, coupling.dem_substeps) DEM steps (particles); 0: run until run.end_time",
            Range::nonNegative());
  s.number("run.end_time", 0.0,
           "when run.steps is 0, steps are taken until the simulated time reaches or passes "
           "this (s)",
           Range::nonNegative());
  s.number("run.memory_limit", 0.0,
           "memory a rank may use (GiB), checked against the estimate before anything large is "
           "allocated; 0: the machine's MemAvailable shared by the ranks on the node",
           Range::nonNegative());
  s.number("run.progress_interval_s", 2.0,
           "seconds of rank 0's wall clock between progress rows (run.progress_columns); the "
           "first and the last step always get one (0: no progress table)",
           Range::nonNegative());
  s.nameList(
      "run.progress_columns", {"step", "time", "dt", "ke", "cfl", "p_iter", "steps_per_s", "left"},
      "the columns of the progress table (LAMMPS's thermo_style; a list, or names "
      "separated by commas): step, time (s), dt (s, of the last step), particles "
      "(global count), ke (translational kinetic energy of the particles, J), contacts "
      "(particle-particle contacts per particle), cfl (the fluid's CFL number of the "
      "last step), p_iter (pressure iterations of the last solve), p_iter_avg (per "
      "solve over the run), dp (rho_f (p_bottom - p_top) between the lowest and the "
      "highest layer of cells along gravity, Pa), wall_per_step (s, since the last "
      "row), steps_per_s (over this run), left (estimated wall seconds to the end), "
      "t_fluid (K, the fluid's mean temperature weighted by eps: fluid.heat), "
      "t_particles (K, the particles' mass-weighted mean temperature: particles.heat); "
      "or any number of report.json by its key path with dots (LAMMPS's thermo_style "
      "custom), e.g. fluid.cfl_last, particles.heat.temperature_max, "
      "timers.dem_force.max, bed.bed_height_m, fluid.drag_force.2: computed at each row "
      "(the report's collectives then), refused at the set-up when the run's report has "
      "no such number; '-' where the run has no such value (docs/output.md); each at most once",
      progressColumnNames(), /*dottedNames=*/true, /*unique=*/true);
  s.boolean("run.timer_sync", false,
            "timed barriers before the fluid's halo after the momentum predictor and before "
            "the DEM's rebuild vote in every sub-step: a rank's wait for the slowest one is "
            "booked to `sync` (fractions.wait) instead of the exchange that follows; for "
            "measuring load imbalance (costs one barrier each)");
  s.number("run.failure_wait_s", 10.0,
           "seconds a rank that failed alone waits for the others to learn of it at the next "
           "error check; past it, it prints its message and stops every rank (MPI_Abort), so "
           "no failure hangs (docs/robustness.md); at most 1e6 s",
           Range::openClosed(0.0, 1e6));
}

const std::vector<std::string>& progressColumnNames() {
  static const std::vector<std::string> names = {
      "step",          "time",        "dt",     "particles",  "ke",
      "contacts",      "cfl",         "p_iter", "p_iter_avg", "dp",
      "wall_per_step", "steps_per_s", "left",   "t_fluid",    "t_particles"};
  return names;
}

RunMode runMode(const Config& cfg) {
  const auto m = cfg.string("run.mode");
  if (m == "fluid") return RunMode::FluidOnly;
  if (m == "particles") return RunMode::ParticlesOnly;
  if (m == "dummy_dem") return RunMode::DummyDem;
  return RunMode::Coupled;
}

const char* runModeName(RunMode m) {
  switch (m) {
    case RunMode::Coupled:
      return "coupled";
    case RunMode::FluidOnly:
      return "fluid";
    case RunMode::ParticlesOnly:
      return "particles";
    case RunMode::DummyDem:
      return "dummy_dem";
  }
  return "?";
}

}  // namespace coloc
