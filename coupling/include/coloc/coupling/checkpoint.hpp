// coloc/coupling/checkpoint.hpp — restart checkpoints: the complete state of a Simulation in ONE
// parallel HDF5 file (collective I/O through io/h5io.hpp), readable on any decomposition
// of the same grid (docs/output.md, "Checkpoints and restart").
//
//   /                     attributes format "coloc-checkpoint", version, status ("ok" |
//                         "failed: <message>"), case, mode, ranks, step, time, config (JSON)
//   /grid                 attributes origin, length, cells, periodic ([3] each)
//   /partition            strategy; /partition/fluid: dims, cuts_{x,y,z} (a process grid) or
//                         boxes_lo, boxes_hi ([ranks x 3], tiled); /partition/particles: dims,
//                         cuts_{x,y,z} (independent mode)
//   /simulation           the Simulation's counters (time, steps, substeps, last_dt, ...)
//   /fluid                u_x u_y u_z (faces), p eps eps_old K (cells), KUp [nz][ny][nx][3],
//                         H_x H_y H_z (AB2 history, faces) + the solver's counters as attributes
//   /particles            id material x v omega f torque f_ext radius mass (rows by rank) +
//                         time, steps, rebuilds, count, flow; particles.heat: extra/temperature,
//                         extra/heat_ext, attribute heat (the energy accounts' totals) and
//                         heat_shares [ranks][3] (each writing rank's wall, ext, outflow terms)
//   /particles/contacts   holder partner shear [M][3] roll [M][3]
//
// Every function is collective over the communicator of the file or the decomposition.
// Errors (missing or corrupt file, another grid, a failed checkpoint) are coloc::Error on every
// rank, with the file name.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "coloc/core/config.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/coupling/layouts.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/io/h5io.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc::coupling {

/// The coupled run's own counters: the state besides the fields and particles that a restart
/// reads back and a re-balance carries over.
struct RunCounters {
  double time = 0, lastDt = 0, lastStepDt = 0;
  long long steps = 0, substeps = 0;
  double momentumResidual = 0, solidVolume = 0, accelL1 = 0;
  std::array<double, 3> particleImpulse{}, fluidImpulse{};
  /// Convection: the worst mismatch over the run between the heat the particles received and
  /// the heat the fluid lost in a step, relative to the gross exchanged heat sum |q| dt.
  double heatResidual = 0;
  /// Convection: the heat exchanged between the fluid and the particles over the run, sum over
  /// the steps and particles of |q| dt (J): the scale of checks.energy_balance.
  double heatExchanged = 0;
};
/// The counters as attributes of `group` (created), and back (one table, checkpoint.cpp).
void writeRunCounters(H5File& file, const std::string& group, const RunCounters& c);
RunCounters readRunCounters(H5File& file, const std::string& group);

inline constexpr const char* kCheckpointFormat = "coloc-checkpoint";
inline constexpr long long kCheckpointVersion = 1;

/// What a checkpoint says about itself (the same on every rank).
struct CheckpointInfo {
  std::string path, status, caseName, mode, strategy, config;
  long long version = 0, steps = 0, ranks = 0;
  double time = 0;
  GlobalGrid grid;
  std::array<std::vector<int>, 3> fluidCuts, particleCuts;  // particleCuts: independent mode
  std::vector<Int3> fluidBoxLo, fluidBoxHi;                 // tiled: every rank's box
  bool ok() const { return status == "ok"; }
};

/// Reads the attributes of `path` (not its arrays). Collective; coloc::Error on every rank when
/// the file is missing, not HDF5, or not a coloc checkpoint.
CheckpointInfo readCheckpointInfo(const Comm& comm, const std::string& path);
/// readCheckpointInfo, then checks the file can restart a run of `grid` in `mode`: status "ok",
/// the same grid (cells, origin, length, periodicity) and run mode. Collective.
CheckpointInfo checkRestartable(const Comm& comm, const std::string& path, const GlobalGrid& grid,
                                RunMode mode);

// ---- the pieces (Simulation::writeCheckpoint and the restoring constructor use them) --------

void writeGrid(H5File& file, const GlobalGrid& grid);
void writeCuts(H5File& file, const std::string& prefix, const Decomposition& dec);
/// Fields (owned values), AB2 history and counters of the fluid to group `group`.
void writeFluidState(H5File& file, const std::string& group, const Decomposition& dec,
                     const fv::FluidSolver& fluid);
/// The inverse on `dec` (any decomposition of the same grid): fields, history, then
/// FluidSolver::restoreState.
void readFluidState(H5File& file, const std::string& group, const Decomposition& dec,
                    fv::FluidSolver& fluid);
/// Each rank's owned particles as rows of global arrays (rank order), contacts likewise.
void writeDemState(H5File& file, const std::string& group, const dem::DemState& s);
/// An even share of the rows on each rank (the restoring DemSolver sends them to their owners).
dem::DemState readDemState(H5File& file, const std::string& group);
/// Semantic checks of a restored particle state (collective): ids non-negative and unique over
/// all ranks, mass and radius positive and finite, materials among the case's `materials`,
/// positions finite and inside the box (any value along a periodic axis), velocities, forces and
/// energy accounts finite, every contact history held by and pointing at an existing particle.
/// Throws Error on every rank naming the file `path` and the dataset.
void validateDemState(const Comm& comm, const dem::DemState& s, const GlobalGrid& grid,
                      std::size_t materials, const std::string& path,
                      const std::string& group = "/particles");
/// The /partition group: strategy, cost weights and imbalances of `L`, the cuts of the blocks.
void writeLayouts(H5File& file, const Layouts& L, const Decomposition& fluid,
                  const std::optional<Decomposition>& particles);
/// The cost weights and imbalances of the /partition group into `L`.
void readLayoutCosts(H5File& file, Layouts& L);
/// The owned particles without contact histories (when DemSolver::saveState cannot run: the
/// state at a failure).
dem::DemState rawDemState(const dem::ParticleStore& p, double time, long long steps);

}  // namespace coloc::coupling
