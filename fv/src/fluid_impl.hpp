// fv/src/fluid_impl.hpp — the fluid solver's state and the verbs of its step (private).
//
// step.cpp holds the step (predictVelocity, assemblePressureRhs, solvePressure, project,
// recordBalances, finishStep) and what it calls every step; fluid.cpp the construction, the
// public accessors, state save/restore, the cell-centred outputs and the diagnostics.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <vector>

#include "boundary.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/partition/halo.hpp"
#include "momentum.hpp"
#include "params.hpp"
#include "pressure_solver.hpp"

namespace coloc::fv {

inline constexpr int kGhost = 2;

/// Run fn(flatFaceIndex, flatCellIndex) over a box of faces of component d (same (i,j,k)).
template <class F>
inline void forFaces(const Field3<double>& u, const Field3<double>& cell, const IndexBox& b,
                     F&& fn) {
  for (int k = b.lo[2]; k < b.hi[2]; ++k)
    for (int j = b.lo[1]; j < b.hi[1]; ++j) {
      const std::ptrdiff_t q0 = u.index(b.lo[0], j, k), c0 = cell.index(b.lo[0], j, k);
      for (int i = 0; i < b.hi[0] - b.lo[0]; ++i) fn(q0 + i, c0 + i);
    }
}

struct FluidSolver::Impl {
  const Decomposition& dec;
  Timers& timers;
  FluidFields f;
  FluidParams prm;  // the case's fluid.* keys, parsed once
  Real3 h;
  MomentumParams mom;
  const BoxBc& bc;       // prm.bc
  bool singular = true;  // no Dirichlet pressure face: the pressure is defined up to a constant
  // Work arrays (allocated once).
  FaceField M;                           // mass fluxes eps_f u
  std::array<Field3<double>, 3> Hn, Ho;  // explicit terms at n and n-1
  FaceField uPrev;
  std::vector<double> matrix, rhs, sol;
  // a row of cells' work: 6 face weights a cell (assembleMatrix), squared scale terms
  // (assemblePressureRhs)
  std::vector<double> rowWork;
  std::unique_ptr<PressureSolver> ps;
  HaloPlan cellHalo;
  std::array<HaloPlan, 3> faceHalo;
  // State.
  bool uGhostsFresh = false, coefficientsChanged = true, haveOld = false, ratesStale = false;
  // A superficial inlet reads eps in the ghost cells next to the face (U / eps of the adjacent
  // cell, tangential ghosts included): those ghosts must be current when the velocity ghosts are
  // filled, also when edit() was written outside a step (e.g. the coupling's set-up).
  bool superficialInlet = false, epsGhostsFresh = false;
  double time = 0, dtOld = 0, matrixDt = -1;
  bool anyK = false;
  long long steps = 0;
  long long itSum = 0, solves = 0;
  long long unconverged = 0;  // pressure solves above the tolerance (this run)
  int itMax = 0, itLast = 0;
  double resLast = 0;
  double maxRate = 0;  // max over cells of sum_d |u_d|/h_d (1/s), after the last step
  double cflLast = 0, dtLast = 0, steadyResidual = std::numeric_limits<double>::infinity();
  double rhsScaleLast = 0;
  // The pressure set-up reuse (prm.reuse; FluidCounters says what each holds).
  double setupDt = -1;
  long long setupReuses = 0, setupIterations = -1;
  bool setupDue = false;
  long long setupsDone = 0;  // multigrid set-ups of the run (a restore's rebuild not counted)
  double inLocal = 0, outLocal = 0, dVolLocal = 0;  // last step, this rank
  double dVolGrossLocal = 0;  // sum over the cells of |d eps/dt| V_cell, last step, this rank
  double umaxLast = 0;        // max |u| over the faces after the last step (global)
  Real3 dragLocal{0, 0, 0};
  // fluid.heat (heat.cpp): work array, ghosts, energy accounting (global sums, J).
  std::vector<double> heatWork;
  bool tGhostsFresh = true, heatStarted = false;
  double heatEnthalpy0 = 0, heatSourceTotal = 0;
  bool heatImplicit = false;  // this step's inputs gave a heat coefficient (CouplingInputs)
  std::array<double, 6> heatFace{0, 0, 0, 0, 0, 0};
  long long heatSubstepsLast = 0;

  Impl(const Decomposition& d, const Config& cfg, Timers& t);
  IndexBox interiorFaces(int c) const {
    IndexBox b{{0, 0, 0}, dec.cells()};
    if (dec.atLowBoundary(c)) b.lo[c] = 1;
    return b;
  }

  // ---- the step (step.cpp) ----------------------------------------------------------------
  void step(double dt);
  /// The coupling's inputs (owned cells) into f.eps, K, KUp; marks what depends on them.
  void takeInputs(const CouplingInputs& in);
  /// Halos and zero-gradient ghosts of the cell inputs eps^{n+1}, eps^n, K, K u_p.
  void exchangeInputs();
  /// Halo and boundary ghosts of u (and, for a superficial inlet, of eps first).
  void fillGhosts();
  /// u* from the momentum equation with semi-implicit drag; u^n kept in uPrev; halo of u*.
  void predictVelocity(double dt);
  /// The pressure matrix when its coefficients changed, the right-hand side -div(eps u*) -
  /// d eps/dt for q = p dt, its flux scale, the warm start; the volume change of the step.
  void assemblePressureRhs(double dt);
  /// The pressure matrix of this step's eps, K and dt to hypre (setOperator).
  void assembleMatrix(double dt);
  /// The pressure matrix of e, K (ghosts current) and dt into `matrix`; anyK from it.
  void fillMatrix(const CellField& e, const CellField& K, double dt);
  /// `matrix` to hypre as the new operator: a multigrid set-up on it, or the hierarchy kept
  /// (prm.reuse: fewer than setup_interval operators served and no solve asked for one).
  void setOperator(double dt);
  /// A multigrid set-up on `matrix` (this step's eps and K at dt), which it keeps.
  void setUpPressure(double dt);
  /// restoreState's part: the hierarchy set up again on the operator of the state's last set-up
  /// and the state's operator given to it (or, without them, a set-up at the next step).
  void restorePressure(const FluidCounters& c);
  void interiorCells(int j, int k, int& i0, int& i1) const;
  /// PCG on the pressure equation; iteration counters.
  void solvePressure();
  /// p from q; u^{n+1} = u* - eps_f/(eps_f + K_f dt) grad q on interior and outlet faces.
  void project(double dt);
  /// Volume fluxes through the box faces and the drag the fluid received (this rank).
  void recordBalances();
  /// eps^n <- eps^{n+1}, counters, the CFL / finite-value check and the velocity rates.
  void finishStep(double dt);
  void computeRates(double dt);
  void boundaryFluxes(double& in, double& out) const;

  // ---- the energy equation (heat.cpp) -------------------------------------------------------
  /// Sub-steps of the explicit energy update with the projected face fluxes; accounting.
  void heatStep(double dt);
  /// Heat into owned cell (i, j, k) per rho_f c_f (K m^3/s) from the temperatures T; box faces
  /// add theirs to bnd[2 axis + side]; rate += sum over the faces of |F_f| + D_f.
  double heatFluxes(const double* T, int i, int j, int k, double* bnd, double& rate) const;
  /// rho_f c_f V sum eps T over the owned cells (J), with the given eps (eps^n or eps^{n+1}).
  double localEnthalpy(const CellField& eps) const;
  void refreshTemperatureGhosts();
};

}  // namespace coloc::fv
