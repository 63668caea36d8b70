#include "pressure_solver.hpp"

#include <HYPRE_utilities.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "coloc/core/error.hpp"

namespace coloc::fv {

void ensureHypreInitialized() {
  static bool done = false;
  if (!done) {
    HYPRE_Init();
    done = true;
  }
}

namespace {
void check(HYPRE_Int err, const char* what) {
  // hypre flags a PCG that stopped at max_iter with HYPRE_ERROR_CONV: not an error here (the
  // fluid reports iterations and residual); anything else is.
  if (err != 0 && !(err & HYPRE_ERROR_CONV)) {
    char msg[256];
    HYPRE_DescribeError(err, msg);
    HYPRE_ClearAllErrors();
    throw Error(std::string("hypre: ") + what + " failed: " + msg);
  }
  if (err) HYPRE_ClearAllErrors();
}
}  // namespace

PressureSolver::PressureSolver(const Decomposition& dec, const Options& options)
    : comm_(dec.comm().raw()), opt_(options) {
  ensureHypreInitialized();
  const auto& g = dec.grid();
  for (int d = 0; d < 3; ++d) {
    ilower_[d] = dec.lo()[d];
    iupper_[d] = dec.hi()[d] - 1;
  }
  check(HYPRE_StructGridCreate(comm_, 3, &grid_), "grid create");
  check(HYPRE_StructGridSetExtents(grid_, ilower_, iupper_), "grid extents");
  HYPRE_Int period[3];
  for (int d = 0; d < 3; ++d) period[d] = g.periodic[d] ? g.cells[d] : 0;
  check(HYPRE_StructGridSetPeriodic(grid_, period), "grid periodic");
  check(HYPRE_StructGridAssemble(grid_), "grid assemble");

  HYPRE_Int offsets[7][3] = {{0, 0, 0}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0},
                             {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  check(HYPRE_StructStencilCreate(3, 7, &stencil_), "stencil create");
  for (int e = 0; e < 7; ++e)
    check(HYPRE_StructStencilSetElement(stencil_, e, offsets[e]), "stencil");

  check(HYPRE_StructMatrixCreate(comm_, grid_, stencil_, &A_), "matrix create");
  check(HYPRE_StructMatrixInitialize(A_), "matrix init");
  check(HYPRE_StructVectorCreate(comm_, grid_, &b_), "vector create");
  check(HYPRE_StructVectorInitialize(b_), "vector init");
  check(HYPRE_StructVectorCreate(comm_, grid_, &x_), "vector create");
  check(HYPRE_StructVectorInitialize(x_), "vector init");
}

PressureSolver::~PressureSolver() {
  destroySolver();
  if (x_) HYPRE_StructVectorDestroy(x_);
  if (b_) HYPRE_StructVectorDestroy(b_);
  if (A_) HYPRE_StructMatrixDestroy(A_);
  if (stencil_) HYPRE_StructStencilDestroy(stencil_);
  if (grid_) HYPRE_StructGridDestroy(grid_);
}

void PressureSolver::destroySolver() {
  if (pcg_) HYPRE_StructPCGDestroy(pcg_);
  if (mg_) {
    if (opt_.kind == Kind::Pfmg)
      HYPRE_StructPFMGDestroy(mg_);
    else
      HYPRE_StructSMGDestroy(mg_);
  }
  pcg_ = mg_ = nullptr;
  ready_ = false;
}

void PressureSolver::createMultigrid(bool asPreconditioner) {
  // As PCG's preconditioner: one cycle from a zero guess, no stopping test. Alone: cycles from
  // the caller's guess until the relative test that solve() sets (logging for the residual).
  const int maxIter = asPreconditioner ? 1 : opt_.maxIter;
  const int logging = asPreconditioner ? 0 : 1;
  if (opt_.kind == Kind::Pfmg) {
    check(HYPRE_StructPFMGCreate(comm_, &mg_), "PFMG create");
    HYPRE_StructPFMGSetMaxIter(mg_, maxIter);
    HYPRE_StructPFMGSetTol(mg_, 0.0);
    if (asPreconditioner)
      HYPRE_StructPFMGSetZeroGuess(mg_);
    else
      HYPRE_StructPFMGSetNonZeroGuess(mg_);
    HYPRE_StructPFMGSetRelaxType(mg_, static_cast<HYPRE_Int>(opt_.relax));
    HYPRE_StructPFMGSetRAPType(mg_, static_cast<HYPRE_Int>(opt_.rap));
    HYPRE_StructPFMGSetNumPreRelax(mg_, opt_.preSweeps);
    HYPRE_StructPFMGSetNumPostRelax(mg_, opt_.postSweeps);
    HYPRE_StructPFMGSetSkipRelax(mg_, opt_.skipRelax ? 1 : 0);
    HYPRE_StructPFMGSetLogging(mg_, logging);
  } else {
    check(HYPRE_StructSMGCreate(comm_, &mg_), "SMG create");
    HYPRE_StructSMGSetMemoryUse(mg_, 0);
    HYPRE_StructSMGSetMaxIter(mg_, maxIter);
    HYPRE_StructSMGSetTol(mg_, 0.0);
    if (asPreconditioner)
      HYPRE_StructSMGSetZeroGuess(mg_);
    else
      HYPRE_StructSMGSetNonZeroGuess(mg_);
    HYPRE_StructSMGSetNumPreRelax(mg_, opt_.preSweeps);
    HYPRE_StructSMGSetNumPostRelax(mg_, opt_.postSweeps);
    HYPRE_StructSMGSetLogging(mg_, logging);
  }
}

void PressureSolver::setValues(std::span<double> values) {
  HYPRE_Int entries[7] = {0, 1, 2, 3, 4, 5, 6};
  check(HYPRE_StructMatrixSetBoxValues(A_, ilower_, iupper_, 7, entries, values.data()),
        "matrix values");
  check(HYPRE_StructMatrixAssemble(A_), "matrix assemble");
}

void PressureSolver::updateMatrix(std::span<double> values) {
  if (!ready_) throw Error("PressureSolver::updateMatrix before setMatrix");
  // PFMG and SMG keep hypre_StructMatrixRef(A) as their finest level and rebind it at every
  // solve (pfmg_solve.c, smg_solve.c); PCG's matvec reads A: new values in place reach both.
  setValues(values);
}

void PressureSolver::setMatrix(std::span<double> values) {
  setValues(values);

  // hypre's PFMG/SMG setup keeps its hierarchy inside the solver object; a new matrix needs a
  // new setup, done on fresh objects (re-running Setup on the same objects leaks the old levels).
  destroySolver();
  const bool pfmg = opt_.kind == Kind::Pfmg;
  createMultigrid(opt_.pcg);
  if (opt_.pcg) {
    check(HYPRE_StructPCGCreate(comm_, &pcg_), "PCG create");
    HYPRE_StructPCGSetTol(pcg_, opt_.tol);
    HYPRE_StructPCGSetAbsoluteTol(pcg_, 0.0);
    HYPRE_StructPCGSetMaxIter(pcg_, opt_.maxIter);
    HYPRE_StructPCGSetTwoNorm(pcg_, 1);
    HYPRE_StructPCGSetRelChange(pcg_, 0);
    HYPRE_StructPCGSetPrintLevel(pcg_, 0);
    HYPRE_StructPCGSetLogging(pcg_, 1);
    HYPRE_StructPCGSetPrecond(pcg_, pfmg ? HYPRE_StructPFMGSolve : HYPRE_StructSMGSolve,
                              pfmg ? HYPRE_StructPFMGSetup : HYPRE_StructSMGSetup, mg_);
    check(HYPRE_StructPCGSetup(pcg_, A_, b_, x_), "PCG setup");
  } else if (pfmg) {
    check(HYPRE_StructPFMGSetup(mg_, A_, b_, x_), "PFMG setup");
  } else {
    check(HYPRE_StructSMGSetup(mg_, A_, b_, x_), "SMG setup");
  }
  ready_ = true;
  ++setups_;
}

int PressureSolver::solve(std::span<double> b, std::span<double> x, double scale) {
  if (!ready_) throw Error("PressureSolver::solve before setMatrix");
  double bb = 0;
  for (double v : b) bb += v * v;
  double bsum = 0;
  MPI_Allreduce(&bb, &bsum, 1, MPI_DOUBLE, MPI_SUM, comm_);
  const double bnorm = std::sqrt(bsum);
  check(HYPRE_StructVectorSetBoxValues(b_, ilower_, iupper_, b.data()), "rhs values");
  check(HYPRE_StructVectorAssemble(b_), "rhs assemble");
  check(HYPRE_StructVectorSetBoxValues(x_, ilower_, iupper_, x.data()), "guess values");
  check(HYPRE_StructVectorAssemble(x_), "guess assemble");
  HYPRE_Int it = 0;
  HYPRE_Real res = 0;
  if (opt_.pcg) {
    HYPRE_StructPCGSetAbsoluteTol(pcg_, opt_.tol * scale);
    check(HYPRE_StructPCGSolve(pcg_, A_, b_, x_), "PCG solve");
    HYPRE_StructPCGGetNumIterations(pcg_, &it);
    HYPRE_StructPCGGetFinalRelativeResidualNorm(pcg_, &res);
  } else {
    // The cycles' own test is relative to ||b||: the same ||r|| <= tol max(||b||, scale).
    const double rel = bnorm > 0 ? opt_.tol * std::max(bnorm, scale) / bnorm : opt_.tol;
    if (opt_.kind == Kind::Pfmg) {
      HYPRE_StructPFMGSetTol(mg_, rel);
      check(HYPRE_StructPFMGSolve(mg_, A_, b_, x_), "PFMG solve");
      HYPRE_StructPFMGGetNumIterations(mg_, &it);
      HYPRE_StructPFMGGetFinalRelativeResidualNorm(mg_, &res);
    } else {
      HYPRE_StructSMGSetTol(mg_, rel);
      check(HYPRE_StructSMGSolve(mg_, A_, b_, x_), "SMG solve");
      HYPRE_StructSMGGetNumIterations(mg_, &it);
      HYPRE_StructSMGGetFinalRelativeResidualNorm(mg_, &res);
    }
  }
  check(HYPRE_StructVectorGetBoxValues(x_, ilower_, iupper_, x.data()), "solution values");
  lastResidual_ = res;
  lastResidualNorm_ = res * bnorm;
  // The stopping test of both paths: ||r|| <= tol max(||b||, scale) (a little slack for the
  // solvers' own round-off in forming the norm).
  lastTarget_ = opt_.tol * std::max(bnorm, scale);
  lastConverged_ = !(lastResidualNorm_ > lastTarget_ * (1 + 1e-6));
  return static_cast<int>(it);
}

}  // namespace coloc::fv
