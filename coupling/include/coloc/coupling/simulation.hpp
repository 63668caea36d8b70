// coloc/coupling/simulation.hpp — one simulation state and the coupled time step.
//
// The Simulation owns the decomposition shared by both physics, the fluid solver, the DEM, the
// timers and the coupling buffers; nothing is global. One coupled step reads as the algorithm
// (docs/benchmarks.md and docs/fv.md, docs/dem.md for the models):
//
//   waitForSlowestRank()         timed barrier: load imbalance -> sync       (wait)
//   computeStencils()            particles' kernel cells and weights         (coupling)
//   fluidForDrag()               the fields eps^n, u^n, grad p^n to sample   (coupling)
//   evaluateDrag()               range by range of particles: the fields     (coupling)
//                                sampled at them, beta_i from the drag law
//   depositParticles()           V_p, beta, beta v_p -> cells                (coupling)
//   waitForSlowestRank()                                                     (wait)
//   sumDepositsAcrossBlocks()    reverse halo sum over block faces           (inter-physics,
//   remote) updateFluidCoefficients()    eps^{n+1} = clip(1 - solid), K, K u_p       (coupling)
//   advanceFluid()               fv::FluidSolver::step                      (fluid)
//   refreshCellVelocity()        cell-centred u^{n+1} (and grad p^{n+1})    (fluid)
//   sampleFluidForForces()       u^{n+1}, grad p^{n+1} at the particles      (coupling)
//   applyCouplingForces()        F = beta (u - v) - V_p rho_f grad p         (coupling)
//   applyCouplingHeat()          q = H' (Tmean - T_p) with convection        (coupling)
//   handForcesToParticles()      forces -> the DEM's external force array    (inter-physics, local:
//                                co-located, the force kernel stores into that array directly)
//   advanceParticles()           n_sub DEM sub-steps                         (particles)
//
// Partition strategies (partition.strategy):
//   uniform      one even Cartesian decomposition for both physics (co-located);
//   balanced     one Cartesian decomposition for both, cuts placed by a cell/particle cost model
//                (partition/balance.hpp), still co-located by construction;
//   independent  the baseline the paper argues against (SediFoam-like): the DEM has its own
//                blocks (balanced by particle count, or partition.dem_dims), and every particle's
//                coupling data travels by MPI to the rank owning its cell and the force comes back
//                the same way (gatherParticles / handForcesToParticles through the proxy
//                ParticleTransfer, coupling/transfer.hpp): booked as inter-physics exchange.
//                Same physics, same answers to round-off.
//
// Co-location makes the kernels read the fluid's arrays and the particle arrays of the same rank
// directly: the deposition and interpolation are coupling arithmetic (docs/architecture.md), and
// the only data that moves between the two physics is the reverse halo sum of the deposited fields
// across block faces (remote) and the hand-over of the forces to the DEM (local).
//
// Drag is semi-implicit in the fluid (Xiao & Sun 2011): the fluid's drag term is
// K (u_p~ - u^{n+1}) with K = sum beta'_i / (rho_f V). The particles receive the same force,
// F_i = beta'_i (u^{n+1}(x_i) - v~_i), held constant over the DEM sub-steps, so the momentum the
// fluid loses equals the drag impulse the particles receive to round-off. The coefficient and
// the particle velocity are those of a backward-Euler particle response over the step,
//     beta' = beta / (1 + dt beta / m),   v~ = v^n + dt a_nondrag,
// so that a particle whose relaxation time is shorter than the CFD step relaxes to the fluid
// velocity without overshoot, and a particle at terminal velocity feels exactly its drag
// (the fixed point is unchanged). In DummyDEM mode particles cannot move: beta' = beta, v~ = 0.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/coupling/layouts.hpp"
#include "coloc/coupling/transfer.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/io/output.hpp"
#include "coloc/partition/balance.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/halo.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc::coupling {

class ParticleCoupling;

/// checks.energy_balance of a run with heat on both sides: |gain of the fluid's and the
/// particles' enthalpies - heat in through faces, walls and the particles' inflow and outflow|,
/// relative (the reports' fluid_heat and particles.heat objects).
/// With `exchanged` > 0 (J, the heat the phases exchanged over the run: report.json
/// coupling.heat_transfer.exchanged) the residual is relative to it instead
/// (checks.energy_balance_exchanged).
double energyBalance(const Json& fluidHeat, const Json& particleHeat, double exchanged = 0);

/// Declares the "coupling.*" keys.
void declareConfig(Schema& s);
/// The schema of a whole case file: run, domain, partition, fluid, particles, coupling.
Schema caseSchema();

class Simulation {
 public:
  Simulation(const Comm& world, const Config& cfg);
  /// With explicit blocks (tests, calibration runs).
  Simulation(const Config& cfg, Layouts layouts);
  /// Restart: the state of `checkpoint` (coupling/checkpoint.hpp, written by
  /// writeCheckpoint) on the blocks `layouts`, which may differ from those that wrote it (any rank
  /// count, same grid). Nothing comes from the case's initial condition: the particles are those
  /// of the file (sent to their owners), the fluid fields are read block by block. `cfg` gives
  /// the parameters; run.steps / run.end_time count from the start of the original run. On the
  /// blocks that wrote it the run continues bitwise as the original; on others to round-off.
  /// Collective; coloc::Error on every rank for a missing, corrupt, failed or foreign file.
  Simulation(const Config& cfg, Layouts layouts, const std::string& checkpoint);
  /// Re-balancing in memory: the state of `from` on the blocks `layouts` (same ranks, same grid):
  /// the fluid's fields and AB2 history remapped by box intersections (partition/remap.hpp),
  /// the particles and their contact histories (DemSolver::saveState, which rebuilds `from`'s
  /// neighbour structures) sent to their new owners, the counters copied. The same state as a
  /// checkpoint written by `from` and read on `layouts`, without the file. Collective.
  Simulation(const Config& cfg, Layouts layouts, Simulation& from);
  /// The blocks to restart from `checkpoint` on `world`: those that wrote it when the rank count
  /// and partition.strategy are the same, else chooseLayouts(). Checks the file first.
  static Layouts restartLayouts(const Comm& world, const Config& cfg,
                                const std::string& checkpoint);
  /// The blocks partition.strategy asks for: the particles from the cost probe (layouts.hpp, no
  /// solver); with partition.calibrate_steps a short run on the uniform blocks measures the
  /// weights.
  static Layouts chooseLayouts(const Comm& world, const Config& cfg) {
    return coupling::chooseLayouts(world, cfg);
  }
  ~Simulation();

  /// One coupling step (what it advances depends on run.mode).
  void step();
  bool finished() const;

  RunMode mode() const { return mode_; }
  double time() const { return run_.time; }
  long long steps() const { return run_.steps; }
  long long demSubsteps() const { return run_.substeps; }
  double lastDt() const { return run_.lastDt; }
  const Decomposition& decomposition() const { return dec_; }
  /// The DEM's blocks: the same as decomposition() unless partition.strategy is independent.
  const Decomposition& particleDecomposition() const { return demDec_ ? *demDec_ : dec_; }
  bool independent() const { return demDec_.has_value(); }
  Timers& timers() { return timers_; }
  fv::FluidSolver* fluid() { return fluid_.get(); }
  dem::DemSolver* particles() { return dem_.get(); }

  /// Drag impulse of the last step: what the particles received and what the fluid gained
  /// (global sums, N s; they cancel), and the worst mismatch over the run relative to the gross
  /// exchanged momentum sum_i beta'_i (|u_i| + |v~_i|) dt (the scale of its round-off: when the
  /// slip is small the net impulse is a small difference of large terms).
  std::array<double, 3> particleDragImpulse() const { return run_.particleImpulse; }
  std::array<double, 3> fluidDragImpulse() const { return run_.fluidImpulse; }
  double momentumBalance() const { return run_.momentumResidual; }
  /// L1 norm of the cell-centred fluid acceleration over the last step, sum |du/dt| V (m^4/s^2).
  double fluidAccelerationL1() const { return run_.accelL1; }
  /// Convection: the worst heat mismatch of a step over the run (RunCounters::heatResidual).
  double heatBalance() const { return run_.heatResidual; }
  /// Convection: the largest particle Biot number h d / (6 k_p) seen in this process's steps
  /// (lumped capacitance wants it well below kBiotLimit).
  double biotMax() const { return biotMax_; }
  static constexpr double kBiotLimit = 0.1;
  /// Total solid volume deposited on the cells (global, m^3) after the last deposit.
  double depositedSolidVolume() const { return run_.solidVolume; }

  /// Fields (p, cell-centred u, eps, K) and particles (id, x, v, omega, radius, rank) to HDF5 +
  /// XDMF when the writer says this step is due. Collective.
  void writeOutput(OutputWriter& out);

  /// The timed loop starts: timers().beginRun(), and the throughput of report() counts the
  /// steps from here (a restarted run's own steps).
  void beginRun();
  /// Where the timed loop started (steps, DEM sub-steps) and, for a simulation that takes over
  /// a run (re-balancing), carrying that start and the timers over.
  std::array<long long, 2> runStart() const { return {runStartSteps_, runStartSubsteps_}; }
  void resumeRun(std::array<long long, 2> start, const Timers& timers) {
    runStartSteps_ = start[0];
    runStartSubsteps_ = start[1];
    timers_ = timers;
  }
  /// The complete state to one HDF5 file, atomically (path.tmp renamed once every rank closed
  /// it): fluid fields and AB2 history, the DEM state (DemSolver::saveState, which forces a
  /// neighbour rebuild: the only effect on the run), the counters, the blocks and `status`
  /// ("ok", or "failed: <message>" for the state at a failure; the particles are then taken
  /// as they are if the DEM's snapshot fails too). Collective.
  void writeCheckpoint(const std::string& path, const std::string& status = "ok");

  /// Report entries of the run (collective): throughput, exchange, fractions, checks, ...
  Json report(double wallSeconds) const;

 private:
  // Construction, one phase each (simulation.cpp): where the state comes from (Origin), the run's
  // limits, the fluid, the particles, the counters, then the coupling, started from the case or
  // resumed from the state.
  struct Origin;
  Simulation(const Config& cfg, Layouts layouts, Origin origin);
  void readRunLimits();
  void openCheckpoint(Origin& origin);
  void createFluid(Origin& origin);
  void createParticles(Origin& origin);
  void takeRunCounters(Origin& origin);
  void createCoupling();
  void resumeCoupling();
  void initialiseCoupling();
  void remapFluid(const Simulation& from);
  void waitForSlowestRank();
  void gatherParticles();
  void computeStencils();
  /// The 7 fields the drag samples (eps, u, grad p; smoothed copies with coupling.smoothing).
  using DragFields = std::array<const CellField*, 7>;
  DragFields fluidForDrag();
  /// The fields sampled at the particles, the drag law and the particles' response
  /// (ParticleCoupling; none sampled at set-up: fields null).
  void evaluateDrag(double dt, const DragFields* fields);
  void depositParticles();
  void sumDepositsAcrossBlocks();
  void updateFluidCoefficients();
  void advanceFluid(double dt);
  /// What the coupling hands the fluid for a step: eps^{n+1}, K, K u_p (owned cells).
  fv::CouplingInputs fluidInputs() const;
  void sampleFluidForForces();
  void applyCouplingForces(double dt);
  void applyCouplingHeat(double dt);
  void handForcesToParticles();
  void smoothField(CellField& f);
  const CellField& sampled(const CellField& f, CellField& smoothed);
  void advanceParticles(int n);
  void refreshCellVelocity();

  const Config& cfg_;
  Layouts layouts_;
  Decomposition dec_;
  std::optional<Decomposition> demDec_;
  Timers timers_;
  RunMode mode_;
  std::unique_ptr<fv::FluidSolver> fluid_;
  std::unique_ptr<dem::DemSolver> dem_;

  // The coupling physics at the particles (coupled modes): stencils, sampled fields, drag law
  // and response, deposits, forces (coupling/src/particle_coupling.hpp).
  std::unique_ptr<ParticleCoupling> coupling_;
  long long demSubsteps_ = 0;  // coupling.dem_substeps (0: as many as the fluid's step allows)
  bool coupled_ = false;
  double steadyTol_ = 0;

  // Cell fields on the fluid's cell layout: the deposits (solid volume fraction, K, K u_p; K and
  // K u_p summed across blocks in place) and eps^{n+1}, the fluid's inputs of the step.
  CellField solid_, scratch_, eps_, K_;
  std::array<CellField, 3> KUp_;
  std::array<CellField, 3> uSmooth_, gradPSmooth_;
  // Convection: sum H' T_p (W) and sum H' (W/K) of each cell's particles, deposited with the
  // drag's terms and summed across blocks with them (the fluid's inputs); the step's mean fluid
  // temperature with mirrored wall ghosts, and its smoothed copy.
  bool convects_ = false;
  CellField heatSource_, heatCoefficient_, TMean_, TSmooth_;
  double biotMax_ = 0;
  int smoothingPasses_ = 0;
  std::array<CellField, 3> uCell_, uCellOld_, gradP_;
  HaloPlan halo_;

  // The particles the fluid's rank couples this step. applyCouplingForces() writes the
  // coupling force where the transfer says (co-located: the DEM's fExt itself) and
  // handForcesToParticles() hands it over.
  std::unique_ptr<ParticleTransfer> transfer_;
  ParticleView view_;

  RunCounters run_;
  double endTime_ = 0;
  long long maxSteps_ = 0;
  long long runStartSteps_ = 0, runStartSubsteps_ = 0;  // counters at beginRun() (throughput)
};

}  // namespace coloc::coupling
