// progress.hpp — the progress table of `coloc run` (LAMMPS's thermo output): a header of the
// columns run.progress_columns names, then one aligned row every run.progress_interval_s seconds
// of rank 0's wall clock, and on the first and the last step (docs/output.md).
//
// Rank 0 alone reads the clock; its "a row is due" travels to every rank on the allreduce that
// ends each step anyway (FailureChannel::agree's request), and on the next step every rank takes
// part in one small allreduce of the global columns (particles, ke, contacts, dp, t_fluid,
// t_particles); rank 0 prints. Steps without a row cost no collective; nothing is allocated
// after the construction. A report.json key as a column (a name with a dot: LAMMPS's
// thermo_style custom) costs the report's computation at each row (its collectives, a JSON
// object), never at a step without a row.
#pragma once

#include <fmt/format.h>

#include <array>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"
#include "coloc/coupling/simulation.hpp"
#include "run_log.hpp"

namespace coloc {

class Progress {
 public:
  /// `interval` 0: no table (no header, no rows, no collective). Reads run.progress_columns,
  /// run.steps, run.end_time, gravity and fluid.rho (`cfg` is kept: bed.* columns read it).
  Progress(const Comm& comm, const Config& cfg, double interval, RunLog& log);
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  bool on() const { return interval_ > 0; }
  /// Collective (when on): the header, and the row of the state the run starts from (step 0,
  /// or the step of a restart's checkpoint). Starts the clocks. Throws ConfigError naming
  /// run.progress_columns for a report key the run's report has no number at (collective then
  /// also when off).
  void start(coupling::Simulation& sim);
  /// Rank 0: 1 when its clock says a row is due, for the agreement that ends the step (the
  /// others: 0). The row then comes on the next step (or the last, whichever is first).
  int request() const;
  /// Collective when `due` (which every rank must pass the same: the agreed request, or the
  /// run's last step) and on: the global columns in one allreduce; rank 0 prints the row.
  void row(coupling::Simulation& sim, bool due);

 private:
  enum Column {
    kStep,
    kTime,
    kDt,
    kParticles,
    kKe,
    kContacts,
    kCfl,
    kPIter,
    kPIterAvg,
    kDp,
    kWallPerStep,
    kStepsPerS,
    kLeft,
    kTFluid,
    kTParticles,
    kReport,  // a report.json key (reportKeys_), not one of progressColumnNames()
    kColumns = kReport
  };
  /// The global sums of one row (the allreduce's buffer).
  enum Sum {
    kSumParticles,
    kSumKe,
    kSumContacts,
    kSumPBottom,
    kSumPTop,
    kSumEpsT,
    kSumEps,
    kSumMassT,
    kSumMass,
    kSums
  };
  /// The report a row reads its report columns from (collective): Simulation::report, with
  /// bed.* (diagnostics.hpp) when a column asks for it.
  Json rowReport(coupling::Simulation& sim, double now);
  void print(coupling::Simulation& sim, const std::array<double, kSums>& sums, double now,
             const Json* report);

  const Comm& comm_;
  const Config& cfg_;
  RunLog& log_;
  bool root_;
  double interval_;
  std::vector<Column> columns_;
  std::vector<std::string> reportKeys_;  // the key of each kReport column, in order
  std::vector<Json::json_pointer> reportPointers_;
  bool global_ = false;  // a column that needs the allreduce
  bool bed_ = false;     // a bed.* column
  long long maxSteps_ = 0;
  double endTime_ = 0, rhoF_ = 1;
  std::array<double, 3> gravity_{};
  // Rank 0's clocks: the run's start (this process), the last row.
  double t0_ = 0, lastWall_ = 0, time0_ = 0;
  long long steps0_ = 0, lastSteps_ = 0;
  fmt::memory_buffer line_;  // the row being formatted (reserved: no allocation in the loop)
};

}  // namespace coloc
