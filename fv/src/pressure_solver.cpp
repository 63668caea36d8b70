#include "pressure_solver.hpp"

#include <HYPRE_utilities.h>

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

PressureSolver::PressureSolver(const Decomposition& dec, Kind kind, double tol, int maxIter)
    : comm_(dec.comm().raw()), kind_(kind), tol_(tol), maxIter_(maxIter) {
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
  if (precond_) {
    if (kind_ == Kind::Pfmg)
      HYPRE_StructPFMGDestroy(precond_);
    else
      HYPRE_StructSMGDestroy(precond_);
  }
  pcg_ = precond_ = nullptr;
  ready_ = false;
}

void PressureSolver::setMatrix(std::span<double> values) {
  HYPRE_Int entries[7] = {0, 1, 2, 3, 4, 5, 6};
  check(HYPRE_StructMatrixSetBoxValues(A_, ilower_, iupper_, 7, entries, values.data()),
        "matrix values");
  check(HYPRE_StructMatrixAssemble(A_), "matrix assemble");

  // hypre's PFMG/SMG setup keeps its hierarchy inside the solver object; a new matrix needs a
  // new setup, done on fresh objects (re-running Setup on the same objects leaks the old levels).
  destroySolver();
  check(HYPRE_StructPCGCreate(comm_, &pcg_), "PCG create");
  HYPRE_StructPCGSetTol(pcg_, tol_);
  HYPRE_StructPCGSetAbsoluteTol(pcg_, 0.0);
  HYPRE_StructPCGSetMaxIter(pcg_, maxIter_);
  HYPRE_StructPCGSetTwoNorm(pcg_, 1);
  HYPRE_StructPCGSetRelChange(pcg_, 0);
  HYPRE_StructPCGSetPrintLevel(pcg_, 0);
  HYPRE_StructPCGSetLogging(pcg_, 1);
  if (kind_ == Kind::Pfmg) {
    check(HYPRE_StructPFMGCreate(comm_, &precond_), "PFMG create");
    HYPRE_StructPFMGSetMaxIter(precond_, 1);
    HYPRE_StructPFMGSetTol(precond_, 0.0);
    HYPRE_StructPFMGSetZeroGuess(precond_);
    HYPRE_StructPFMGSetRelaxType(precond_, 2);  // symmetric red-black Gauss-Seidel
    HYPRE_StructPFMGSetRAPType(precond_, 0);    // Galerkin coarse operators
    HYPRE_StructPFMGSetNumPreRelax(precond_, 1);
    HYPRE_StructPFMGSetNumPostRelax(precond_, 1);
    HYPRE_StructPFMGSetSkipRelax(precond_, 0);
    HYPRE_StructPFMGSetLogging(precond_, 0);
    HYPRE_StructPCGSetPrecond(pcg_, HYPRE_StructPFMGSolve, HYPRE_StructPFMGSetup, precond_);
  } else {
    check(HYPRE_StructSMGCreate(comm_, &precond_), "SMG create");
    HYPRE_StructSMGSetMemoryUse(precond_, 0);
    HYPRE_StructSMGSetMaxIter(precond_, 1);
    HYPRE_StructSMGSetTol(precond_, 0.0);
    HYPRE_StructSMGSetZeroGuess(precond_);
    HYPRE_StructSMGSetNumPreRelax(precond_, 1);
    HYPRE_StructSMGSetNumPostRelax(precond_, 1);
    HYPRE_StructPCGSetPrecond(pcg_, HYPRE_StructSMGSolve, HYPRE_StructSMGSetup, precond_);
  }
  check(HYPRE_StructPCGSetup(pcg_, A_, b_, x_), "PCG setup");
  ready_ = true;
  ++setups_;
}

int PressureSolver::solve(std::span<double> b, std::span<double> x, double scale) {
  if (!ready_) throw Error("PressureSolver::solve before setMatrix");
  HYPRE_StructPCGSetAbsoluteTol(pcg_, tol_ * scale);
  check(HYPRE_StructVectorSetBoxValues(b_, ilower_, iupper_, b.data()), "rhs values");
  check(HYPRE_StructVectorAssemble(b_), "rhs assemble");
  check(HYPRE_StructVectorSetBoxValues(x_, ilower_, iupper_, x.data()), "guess values");
  check(HYPRE_StructVectorAssemble(x_), "guess assemble");
  check(HYPRE_StructPCGSolve(pcg_, A_, b_, x_), "PCG solve");
  check(HYPRE_StructVectorGetBoxValues(x_, ilower_, iupper_, x.data()), "solution values");
  HYPRE_Int it = 0;
  HYPRE_StructPCGGetNumIterations(pcg_, &it);
  HYPRE_Real res = 0;
  HYPRE_StructPCGGetFinalRelativeResidualNorm(pcg_, &res);
  lastResidual_ = res;
  double bb = 0;
  for (double v : b) bb += v * v;
  double bsum = 0;
  MPI_Allreduce(&bb, &bsum, 1, MPI_DOUBLE, MPI_SUM, comm_);
  lastResidualNorm_ = res * std::sqrt(bsum);
  return static_cast<int>(it);
}

}  // namespace coloc::fv
