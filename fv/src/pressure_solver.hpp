// fv/src/pressure_solver.hpp — the pressure equation on hypre's Struct interface (private).
//
// One 7-point Struct matrix over the global cell grid (periodic axes passed to
// HYPRE_StructGridSetPeriodic), one right-hand side and one solution vector, solved by PCG
// preconditioned by one V-cycle of PFMG or SMG, or by the multigrid cycle alone iterated to
// the same stopping test (Options::pcg = false). PFMG's smoother, coarse operators and sweeps
// are Options (docs/fv.md, "Pressure solver options"). Grid, stencil, matrix and vectors are
// created once; setMatrix() refreshes the values and sets the multigrid hierarchy up on them;
// updateMatrix() refreshes the values only and keeps the hierarchy of the last setMatrix() as
// the preconditioner (or cycle) of the new operator: its finest level and every residual are
// the new operator's (hypre's PFMG and SMG hold a reference to the matrix object, whose values
// change in place), its coarse levels and transfers the old one's. The fluid decides which
// (docs/fv.md, "Pressure set-up reuse").
//
// Stencil entry order per cell: 0 centre, 1 -x, 2 +x, 3 -y, 4 +y, 5 -z, 6 +z; values are laid
// out entry fastest, then x, y, z over this rank's block (hypre's SetBoxValues order).
#pragma once

#include <HYPRE_struct_ls.h>

#include <span>
#include <string>

#include "coloc/partition/decomposition.hpp"

namespace coloc::fv {

class PressureSolver {
 public:
  enum class Kind { Pfmg, Smg };
  /// PFMG's smoother (hypre's relax_type numbers).
  enum class Relax { Jacobi = 0, WeightedJacobi = 1, RbgsSymmetric = 2, RbgsNonsymmetric = 3 };
  /// PFMG's coarse operators (hypre's rap_type numbers).
  enum class Rap { Galerkin = 0, NonGalerkin = 1 };
  struct Options {
    Kind kind = Kind::Pfmg;
    double tol = 1e-8;  // stopping test, see solve()
    int maxIter = 200;  // iteration cap (PCG iterations, or multigrid cycles without PCG)
    bool pcg = true;    // PCG + one cycle as preconditioner; false: the cycle alone
    Relax relax = Relax::RbgsSymmetric;  // PFMG only, like rap and skipRelax
    Rap rap = Rap::Galerkin;
    bool skipRelax = true;
    int preSweeps = 1, postSweeps = 1;  // per level and cycle (SMG too)
    bool errorOnNoConvergence = false;  // fluid.pressure.on_no_convergence = error
  };
  PressureSolver(const Decomposition& dec, const Options& options);
  PressureSolver(const Decomposition& dec, Kind kind, double tol, int maxIter)
      : PressureSolver(dec, Options{.kind = kind, .tol = tol, .maxIter = maxIter}) {}
  ~PressureSolver();
  PressureSolver(const PressureSolver&) = delete;
  PressureSolver& operator=(const PressureSolver&) = delete;

  /// New matrix values (7 per owned cell, see above); sets the multigrid hierarchy up on them.
  void setMatrix(std::span<double> values);
  /// New matrix values of the same stencil; the hierarchy of the last setMatrix() is kept.
  /// Needs a setMatrix() before.
  void updateMatrix(std::span<double> values);
  /// A hierarchy exists (setMatrix() was called).
  bool ready() const { return ready_; }
  /// Solve A x = b to ||r||_2 <= tol max(||b||_2, scale): `scale` is the norm of the flux scale
  /// of the right-hand side (so a right-hand side that is only round-off does not ask the
  /// solver for round-off digits). `x` holds the initial guess on entry and the solution on
  /// exit (owned cells, x fastest). Returns the iteration count (PCG iterations, or cycles).
  int solve(std::span<double> b, std::span<double> x, double scale);
  double lastResidualNorm() const { return lastResidualNorm_; }
  double lastRelativeResidual() const { return lastResidual_; }
  /// Whether the last solve met its stopping test (not stopped by max_iter above it).
  bool lastConverged() const { return lastConverged_; }
  /// The tolerance of the last solve's stopping test (the norm ||r||_2 had to reach).
  double lastTarget() const { return lastTarget_; }
  const Options& options() const { return opt_; }
  int setups() const { return setups_; }

 private:
  void destroySolver();
  void createMultigrid(bool asPreconditioner);
  void setValues(std::span<double> values);
  MPI_Comm comm_;
  Options opt_;
  HYPRE_Int ilower_[3], iupper_[3];
  HYPRE_StructGrid grid_ = nullptr;
  HYPRE_StructStencil stencil_ = nullptr;
  HYPRE_StructMatrix A_ = nullptr;
  HYPRE_StructVector b_ = nullptr, x_ = nullptr;
  HYPRE_StructSolver pcg_ = nullptr, mg_ = nullptr;
  bool ready_ = false;
  double lastResidual_ = 0, lastResidualNorm_ = 0, lastTarget_ = 0;
  bool lastConverged_ = true;
  int setups_ = 0;
};

/// HYPRE_Init() once per process (after MPI_Init); called by the first FluidSolver.
void ensureHypreInitialized();

}  // namespace coloc::fv
