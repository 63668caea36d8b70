// coloc/fv/fluid.hpp — the volume-averaged incompressible flow solver (docs/fv.md).
//
// Staggered MAC grid on the shared decomposition: p, eps, K, K*u_p at cell centres; u on faces.
// Fractional-step projection; semi-implicit drag (Xiao & Sun 2011); the variable-coefficient
// pressure equation  div( eps^2/A grad p ) = div(eps u*) + (eps^{n+1} - eps^n)/dt  solved with
// hypre Struct PCG + PFMG (SMG selectable).
//
// Contract with coupling/ (do not change without changing the coupling):
//  - the coupling hands the fluid its inputs explicitly: step(dt, CouplingInputs) takes the
//    owned cells of eps^{n+1}, K and KUp (the pressure matrix is then rebuilt); once, before the
//    first step, startCoupling(inputs) makes the initial eps the state at the start too. The
//    fluid keeps its copy (checkpointed with it) and the old level eps^n it needs; step() fills
//    the ghosts (one halo exchange) and copies eps -> eps^n at its end; between steps the
//    coupling reads eps with its ghosts from fields(). Fluid-only cases leave eps = 1 and K = 0
//    (or set them in tests through edit()).
//  - fields() only reads. Writing the state outside a step (initial conditions, tests, restart)
//    goes through edit(), which says so: the next step refreshes every ghost layer, the
//    velocity rate and the pressure matrix.
//  - drag at a face uses the arithmetic mean of the two adjacent cells' K and KUp, and
//    cellVelocity() is the arithmetic mean of the two faces of a cell: the two averages are
//    adjoint, so the drag the fluid loses equals the drag the particles gain to round-off.
//  - K = sum_i beta_i / (rho_f V_cell) [1/s], KUp = sum_i beta_i u_p,i / (rho_f V_cell) [m/s^2].
#pragma once

#include <array>
#include <memory>
#include <type_traits>

#include "coloc/core/config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc::fv {

/// Checks the fluid.boundary.* keys against the grid (types, periodicity, wall velocities) as
/// the solver's construction does, without allocating anything. Throws ConfigError.
void checkBoundaryConfig(const Config& cfg, const GlobalGrid& grid);

/// Declares the "fluid.*" keys of the case file.
void declareConfig(Schema& s);

/// The solver's state beyond the fields and the AB2 history (checkpoint/restart, re-balancing):
/// everything the next step, nextDt() and diagnostics() read. Same value on every rank.
struct FluidCounters {
  double time = 0, dtOld = 0, dtLast = 0, cflLast = 0;
  double maxRate = 0;         // max over cells of sum_d |u_d|/h_d after the last step (1/s)
  double steadyResidual = 0;  // +inf before the first step
  double resLast = 0, rhsScaleLast = 0;
  // Energy accounting (fluid.heat): the enthalpy when the first step started, the heat through
  // each box face (xlo, xhi, ylo, ..., positive into the fluid) and from the source (J).
  double heatEnthalpy0 = 0, heatSource = 0;
  std::array<double, 6> heatFace{0, 0, 0, 0, 0, 0};
  bool heatStarted = false;
  long long steps = 0, itSum = 0, solves = 0, setups = 0;
  long long itMax = 0, itLast = 0;
  // The pressure set-up reuse (fluid.pressure.setup_interval > 1): the dt of the operator the
  // multigrid hierarchy was set up on (< 0: none; its eps and K are the state fields eps_setup
  // and K_setup), the operators it has served since, the iterations of its first solve (-1: not
  // yet), whether a solve asked for a new set-up, and the dt of the current operator (< 0: none).
  double setupDt = -1, matrixDt = -1;
  long long setupReuses = 0, setupIterations = -1;
  bool setupDue = false;
  long long unconverged = 0;  // pressure solves of this run that ended above the tolerance
  bool haveOld = false;       // an AB2 history exists (the next step uses AB2)
  bool ratesStale = false;    // nextDt() recomputes the velocity rate first
};

/// The fluid's inputs from the coupling for one step: fields on the fluid's cell layout, of which
/// the owned cells are read (the ghosts are the fluid's own business).
struct CouplingInputs {
  const CellField& eps;                 // eps^{n+1}
  const CellField& K;                   // sum beta / (rho_f V_cell) (1/s)
  const std::array<CellField, 3>& KUp;  // sum beta u_p / (rho_f V_cell) (m/s^2)
  /// fluid.heat: the heat the particles give the fluid in each cell (W); null: none this step
  /// (the source stays as it was). Ignored with fluid.heat off.
  const CellField* heatSource = nullptr;
  /// fluid.heat, convection: the exchange coefficient of the particles in each cell, sum H (W/K).
  /// With it the particles' heat is point-implicit in the fluid's temperature: each cell receives
  /// heatSource - heatCoefficient T at every heat sub-step, T the cell's new temperature (so
  /// heatSource is sum H T_p), and the step leaves the sub-steps' mean temperature in Tmean (the
  /// temperature the exchange saw, for the particles' side). Null: the explicit source above.
  const CellField* heatCoefficient = nullptr;
};

struct FluidFields {
  FaceField u;                   // face-normal velocity components (m/s)
  CellField p;                   // kinematic pressure p/rho_f (m^2/s^2)
  CellField eps, epsOld;         // fluid volume fraction at n+1 and n
  CellField K;                   // drag coefficient sum beta/(rho_f V) (1/s)
  std::array<CellField, 3> KUp;  // K * mean particle velocity (m/s^2)
  // fluid.heat only (empty, unallocated, when off):
  CellField T;           // fluid temperature (K); ghosts current after a step
  CellField heatSource;  // heat given to the fluid in each cell (W), owned cells read
  // with CouplingInputs::heatCoefficient only (allocated by the first step that gives one):
  CellField heatCoefficient;  // sum H of the cell's particles (W/K)
  CellField Tmean;            // mean of T over the last step's sub-steps (K); halo ghosts current
  // fluid.pressure.setup_interval > 1 only (empty otherwise): eps and K when the pressure's
  // multigrid hierarchy was last set up (a restart or re-balance sets it up again from them).
  CellField epsSetup, KSetup;
};

class FluidSolver {
 public:
  FluidSolver(const Decomposition& dec, const Config& cfg, Timers& timers);
  ~FluidSolver();
  FluidSolver(const FluidSolver&) = delete;
  FluidSolver& operator=(const FluidSolver&) = delete;

  /// The state, read only (no effect on the solver).
  const FluidFields& fields() const;
  /// fluid.heat is on: the fields have T and heatSource, the counters their energy accounts.
  bool hasHeat() const;
  /// The state, to write outside a step (initial conditions, tests, restart): the next step
  /// refreshes every ghost layer and rebuilds the pressure matrix, and nextDt() recomputes the
  /// velocity rate.
  FluidFields& edit();
  /// The coupling's first inputs are also the state at the start: eps^n <- eps^{n+1} (the first
  /// step sees no d(eps)/dt from the constructor's eps = 1), and eps gets its ghosts now (one
  /// exchange), so that the coupling can read it before the first step. Collective; once,
  /// before the first step.
  void startCoupling(const CouplingInputs& in);
  /// For eps written through edit(): eps^n <- eps, ghosts as they are (startCoupling() without
  /// the exchange).
  void syncEpsOld();
  /// Advance one step of size dt with the coupling's inputs of this step (their owned cells).
  void step(double dt, const CouplingInputs& in);
  /// Advance one step of size dt, the inputs as they are (fluid-only runs).
  void step(double dt);
  /// The time step the case asks for now: fixed, or adaptive from CFL and viscous limits.
  /// Collective when adaptive and the fields were written through edit() since the last step
  /// (the velocity rate is then recomputed); call it on every rank.
  double nextDt() const;
  double time() const;
  /// max|u^{n+1}-u^n| / max|u^{n+1}| of the last step (same value on every rank).
  double steadyResidual() const;
  long long stepCount() const;

  // ---- state (checkpoint/restart, re-balancing) --------------------------------------------
  /// The scalar state (local, no communication).
  FluidCounters counters() const;
  /// The AB2 history: the explicit terms H of the last step, one array per face component d on
  /// faceLayout(dec, d, 0) (owned faces; faces the predictor does not advance hold 0).
  const std::array<Field3<double>, 3>& history() const;
  std::array<Field3<double>, 3>& history();
  /// Restore: after the owned values of edit() (u, p, eps, epsOld, K, KUp) and of history()
  /// were overwritten (e.g. read from a checkpoint on any decomposition), refresh every ghost
  /// layer as the step leaves them and take the counters. The pressure's multigrid hierarchy is
  /// set up again on the operator it was set up on (eps_setup, K_setup, setupDt; none: the next
  /// step sets one up). With the same decomposition the run then continues bitwise identically.
  /// Collective.
  void restoreState(const FluidCounters& c);
  /// The fluid's restart table: every array that checkpoints write and read and that a
  /// re-balance remaps, declared once (forEachStateField below walks it).
  struct StateField {
    const char* name;  // dataset name in checkpoint files
    int stagger;       // -1: cell centred; 0, 1, 2: faces normal to that axis
    int components;    // 1, or 3: a cell vector (one dataset)
    bool fraction;     // a fluid fraction: restored values must lie in (0, 1]
    // a checkpoint may lack it (written before it existed or with other settings): the reader
    // then leaves the arrays as they are and tells restoreState (FluidCounters) what that means
    bool optional = false;
  };

  /// Cell-centred velocity (mean of the two faces) with one ghost layer filled.
  void cellVelocity(std::array<CellField, 3>& out);
  /// Cell-centred gradient of the kinematic pressure with one ghost layer filled.
  void pressureGradient(std::array<CellField, 3>& out);

  /// Report entries: pressure.{iterations_avg,iterations_max,iterations_last,residual_last,
  /// rhs_scale_last,setups}, checks.mass_balance, fluid.{steps,time,dt_last,cfl_last,
  /// steady_residual,inflow,outflow,volume_rate,drag_force}. drag_force is the drag the fluid
  /// received in the last step, sum over the faces the predictor advanced of
  /// V (KUp_f - K_f u_f^{n+1}) (per unit fluid density, m^4/s^2): the semi-implicit drag is
  /// implicit in the projected u^{n+1}. With fluid.heat also fluid_heat.{enthalpy,
  /// enthalpy_initial, source_heat, face_heat.{xlo..zhi}, substeps_last} and
  /// checks.fluid_energy_balance (docs/output.md). Collective.
  Json diagnostics() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A fluid-only run (run.mode = fluid): steps of nextDt() until run.steps are done (or, with
/// run.steps = 0, until run.end_time is reached; the last step is shortened to land on it), or
/// until the steady residual falls below fluid.steady_tol (> 0). Collective. Returns
/// {"steps", "sim_time", "stop": "steps" | "end_time" | "steady", "wall_s"}.
Json runFluidOnly(FluidSolver& solver, const Config& cfg);

/// Walks the fluid's restart table in one fixed order: fn(const FluidSolver::StateField&,
/// Field3<double>* const* arrays): three slots, the first `components` hold the arrays (const
/// Field3 for a const solver).
/// The non-const form goes through edit(), so the ghosts and rates count as stale after it.
template <class Solver, class Fn>
void forEachStateField(Solver& fluid, Fn&& fn) {
  using SF = FluidSolver::StateField;
  auto& f = [&]() -> auto& {
    if constexpr (std::is_const_v<Solver>)
      return fluid.fields();
    else
      return fluid.edit();
  }
  ();
  auto& h = fluid.history();
  using Ptr = decltype(&f.p);
  // always three slots (the unused ones null): `components` says how many hold arrays
  const auto visit = [&](const SF& sf, Ptr a0, Ptr a1 = nullptr, Ptr a2 = nullptr) {
    const Ptr a[3] = {a0, a1, a2};
    fn(sf, a);
  };
  static constexpr SF kU[3] = {{"u_x", 0, 1, false}, {"u_y", 1, 1, false}, {"u_z", 2, 1, false}};
  static constexpr SF kH[3] = {{"H_x", 0, 1, false}, {"H_y", 1, 1, false}, {"H_z", 2, 1, false}};
  for (int d = 0; d < 3; ++d) {
    visit(kU[d], &f.u[d]);
    visit(kH[d], &h[static_cast<std::size_t>(d)]);
  }
  visit({"p", -1, 1, false}, &f.p);
  visit({"eps", -1, 1, true}, &f.eps);
  visit({"eps_old", -1, 1, true}, &f.epsOld);
  visit({"K", -1, 1, false}, &f.K);
  visit({"KUp", -1, 3, false}, &f.KUp[0], &f.KUp[1], &f.KUp[2]);
  if (!f.T.data().empty()) {  // fluid.heat (explicit scheme: no history beyond T)
    visit({"T", -1, 1, false}, &f.T);
    visit({"heat_source", -1, 1, false}, &f.heatSource);
  }
  if (!f.epsSetup.data().empty()) {  // the pressure set-up's operator (setup_interval > 1)
    visit({"eps_setup", -1, 1, true, true}, &f.epsSetup);
    visit({"K_setup", -1, 1, false, true}, &f.KSetup);
  }
}

}  // namespace coloc::fv
