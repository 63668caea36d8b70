// The fluid step as its verbs; the equations and choices are documented in docs/fv.md.
//
//   u* = (eps^n u^n / dt + E + eps^{n+1} g + K u_p) / (eps^{n+1}/dt + K)        predictVelocity
//   sum_f w_f (q_P - q_nb) = -div(eps^{n+1} u*) - (eps^{n+1} - eps^n)/dt       assemblePressureRhs
//   q = p dt                                                                   solvePressure
//   u^{n+1} = u* - eps_f/(eps_f + K_f dt) grad q                                project
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "cell_rows.hpp"
#include "coloc/core/failure.hpp"
#include "fluid_impl.hpp"

namespace coloc::fv {

void FluidSolver::Impl::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw Error(fmt::format("fluid step: invalid dt {:f}", dt));
  exchangeInputs();
  if (!uGhostsFresh) fillGhosts();
  predictVelocity(dt);
  assemblePressureRhs(dt);
  solvePressure();
  project(dt);
  recordBalances();
  if (prm.heat.on) heatStep(dt);
  finishStep(dt);
}

void FluidSolver::Impl::exchangeInputs() {
  {
    ScopedPhase t(timers, Phase::FluidHalo);
    Field3<double>* cells[6] = {&f.eps, &f.epsOld, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2]};
    cellHalo.gather(std::span<Field3<double>* const>(cells, 6), &timers, Exchange::IntraPhysics);
  }
  ScopedPhase t(timers, Phase::FluidBoundary);
  applyScalarBc(dec, f.eps);
  applyScalarBc(dec, f.epsOld);
  applyScalarBc(dec, f.K);
  for (auto& k : f.KUp) applyScalarBc(dec, k);
  epsGhostsFresh = true;
}

void FluidSolver::Impl::fillGhosts() {
  if (superficialInlet && !epsGhostsFresh) {
    {
      ScopedPhase t(timers, Phase::FluidHalo);
      cellHalo.gather(f.eps, &timers, Exchange::IntraPhysics);
    }
    ScopedPhase t(timers, Phase::FluidBoundary);
    applyScalarBc(dec, f.eps);
    epsGhostsFresh = true;
  }
  if (superficialInlet) {
    // The inlet face is an owned face that the halo sends, and its value U / eps follows eps:
    // set it before the halo. A block only as thick as the ghost width has the next block's
    // ghost faces reach it (a stale copy there would differ from a serial run).
    ScopedPhase t(timers, Phase::FluidBoundary);
    for (int c = 0; c < 3; ++c) applyVelocityBc(dec, bc, c, f.u[c], &f.eps);
  }
  {
    ScopedPhase t(timers, Phase::FluidHalo);
    for (int c = 0; c < 3; ++c) faceHalo[c].gather(f.u[c], &timers, Exchange::IntraPhysics);
  }
  // The ghosts beyond a boundary face mirror inner faces, which may be halo faces: after it.
  ScopedPhase t(timers, Phase::FluidBoundary);
  for (int c = 0; c < 3; ++c) applyVelocityBc(dec, bc, c, f.u[c], &f.eps);
  uGhostsFresh = true;
}
void FluidSolver::Impl::interiorCells(int j, int k, int& i0, int& i1) const {
  // the cells of row (j, k) without a boundary face: [i0, i1) (empty on a row along one)
  const Int3 n = dec.cells();
  const bool edgeRow = (dec.atLowBoundary(1) && j == 0) ||
                       (dec.atHighBoundary(1) && j == n[1] - 1) ||
                       (dec.atLowBoundary(2) && k == 0) || (dec.atHighBoundary(2) && k == n[2] - 1);
  i0 = edgeRow ? n[0] : (dec.atLowBoundary(0) ? 1 : 0);
  i1 = std::max(i0, dec.atHighBoundary(0) ? n[0] - 1 : n[0]);
  i0 = std::min(i0, i1);
}
void FluidSolver::Impl::fillMatrix(const CellField& e, const CellField& K, double dt) {
  // Row of cell P: sum_f w_f (q_P - q_nb), w_f = eps_f^2 / ((eps_f + K_f dt) h_d^2), q = p dt.
  // An outlet face (Dirichlet p at the face, half a cell away) doubles w and moves the known
  // value to the right-hand side; inlet, wall and slip faces contribute nothing (dp/dn = 0).
  const Int3 n = dec.cells();
  bool localK = false;
  const auto ws = static_cast<std::size_t>(n[0]);
  MatrixRow mrow{};
  for (int a = 0; a < 3; ++a) {
    mrow.cellStride[a] = e.stride(a);
    mrow.h[a] = h[a];
  }
  mrow.dt = dt;
  std::size_t r0 = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j, r0 += ws) {
      const auto cell = [&](int i) {  // one cell, with its boundary faces
        double* row = &matrix[7 * (r0 + static_cast<std::size_t>(i))];
        double diag = 0;
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          const std::ptrdiff_t s = e.stride(a);
          const std::ptrdiff_t c = e.index(i, j, k);
          for (int side = 0; side < 2; ++side) {
            const bool boundary = side == 0 ? (dec.atLowBoundary(a) && idx[a] == 0)
                                            : (dec.atHighBoundary(a) && idx[a] == n[a] - 1);
            double w = 0;
            const std::ptrdiff_t nb = c + (side == 0 ? -s : s);
            const double ef = 0.5 * (e.data()[c] + e.data()[nb]);
            const double kf = 0.5 * (K.data()[c] + K.data()[nb]);
            if (kf != 0.0) localK = true;
            if (!boundary) {
              w = ef * ef / ((ef + kf * dt) * h[a] * h[a]);
              row[1 + 2 * a + side] = -w;
            } else {
              row[1 + 2 * a + side] = 0.0;
              if (bc.atLocal(dec, a, side, i, j, k).type == BcType::Outlet)
                w = outletWeight(ef, kf, dt, h[a]);
            }
            diag += w;
          }
        }
        row[0] = diag;
      };
      int i0 = 0, i1 = 0;
      interiorCells(j, k, i0, i1);
      const std::ptrdiff_t c0 = e.index(0, j, k);
      mrow.eps = e.data().data() + c0;
      mrow.K = K.data().data() + c0;
      if (matrixRow(mrow, i0, i1, rowWork.data(), ws, matrix.data() + 7 * r0)) localK = true;
      for (int i = 0; i < i0; ++i) cell(i);
      for (int i = i1; i < n[0]; ++i) cell(i);
    }
  anyK = dec.comm().max(localK ? 1 : 0) == 1;  // the same rebuild decision on every rank
}
void FluidSolver::Impl::assembleMatrix(double dt) {
  fillMatrix(f.eps, f.K, dt);
  setOperator(dt);
  matrixDt = dt;
  coefficientsChanged = false;
}
void FluidSolver::Impl::setOperator(double dt) {
  // Every rank decides alike: the counts and the iteration numbers are global.
  if (!ps->ready() || setupDue || setupReuses + 1 >= prm.reuse.interval) {
    setUpPressure(dt);
  } else {
    ps->updateMatrix(matrix);
    ++setupReuses;
  }
}
void FluidSolver::Impl::setUpPressure(double dt) {
  {
    ScopedPhase t(timers, Phase::FluidPressureSetup);
    ps->setMatrix(matrix);
  }
  ++setupsDone;
  setupReuses = 0;
  setupIterations = -1;
  setupDue = false;
  setupDt = dt;
  if (prm.reuse.on()) {  // its operator, for a restart or a re-balance to set it up again
    std::copy(f.eps.data().begin(), f.eps.data().end(), f.epsSetup.data().begin());
    std::copy(f.K.data().begin(), f.K.data().end(), f.KSetup.data().begin());
  }
}
void FluidSolver::Impl::restorePressure(const FluidCounters& c) {
  setupDt = -1;
  setupReuses = 0;
  setupIterations = -1;
  setupDue = true;  // the hierarchy held (if any) is not the state's
  matrixDt = -1;    // the next step assembles the operator and sets it up
  coefficientsChanged = true;
  if (!prm.reuse.on() || c.setupDt < 0) return;
  // The set-up's operator with its ghosts as the step's input exchange gave them, set up as
  // then (not counted: the run's set-ups are those it decided), then the state's own operator.
  Field3<double>* cells[2] = {&f.epsSetup, &f.KSetup};
  cellHalo.gather(std::span<Field3<double>* const>(cells, 2));
  applyScalarBc(dec, f.epsSetup);
  applyScalarBc(dec, f.KSetup);
  fillMatrix(f.epsSetup, f.KSetup, c.setupDt);
  ps->setMatrix(matrix);
  setupDt = c.setupDt;
  setupReuses = c.setupReuses;
  setupIterations = c.setupIterations;
  setupDue = c.setupDue;
  if (c.matrixDt >= 0) {
    fillMatrix(f.eps, f.K, c.matrixDt);
    ps->updateMatrix(matrix);
    matrixDt = c.matrixDt;
    coefficientsChanged = false;
  }
}
void FluidSolver::Impl::computeRates(double dt) {
  // CFL per cell: dt sum_d max(|u_lo|,|u_hi|)/h_d; NaN/Inf anywhere stops the run; the steady
  // residual is max|u^{n+1}-u^n| / max|u^{n+1}|.
  const Int3 n = dec.cells();
  double rate = 0, du = 0, umax = 0;
  Int3 at{0, 0, 0};
  std::string err;
  // Row by row: the per-cell values through ratesRow (cell_rows.hpp), then the maxima in cell
  // order; a cell with a non-finite face velocity is named by the cell-by-cell check below.
  const auto ws = static_cast<std::size_t>(n[0]);
  const double* const rr = rowWork.data();
  RatesRow row{};
  for (int a = 0; a < 3; ++a) {
    row.faceStride[a] = f.u[a].stride(a);
    row.h[a] = h[a];
  }
  const auto badCell = [&](int i, int j, int k) {
    for (int a = 0; a < 3; ++a) {
      const auto& U = f.u[a];
      const double lo = U(i, j, k);
      const double hi = U(i + (a == 0), j + (a == 1), k + (a == 2));
      if (!std::isfinite(lo) || !std::isfinite(hi)) {
        err = fmt::format(
            "fluid step {}: non-finite velocity u_{} = {:g} at cell ({}, {}, {}) (global index)",
            steps, "xyz"[a], std::isfinite(lo) ? hi : lo, dec.lo()[0] + i, dec.lo()[1] + j,
            dec.lo()[2] + k);
        return;
      }
    }
  };
  for (int k = 0; k < n[2] && err.empty(); ++k)
    for (int j = 0; j < n[1] && err.empty(); ++j) {
      for (int a = 0; a < 3; ++a) {
        row.u[a] = f.u[a].data().data() + f.u[a].index(0, j, k);
        row.uPrev[a] = dt > 0 ? uPrev[a].data().data() + uPrev[a].index(0, j, k) : nullptr;
      }
      ratesRow(row, n[0], rowWork.data(), ws);
      for (int i = 0; i < n[0]; ++i) {
        if (rr[3 * ws + static_cast<std::size_t>(i)] != 0.0) {
          badCell(i, j, k);
          break;
        }
        const double r = rr[static_cast<std::size_t>(i)];
        umax = std::max(umax, rr[ws + static_cast<std::size_t>(i)]);
        if (dt > 0) du = std::max(du, rr[2 * ws + static_cast<std::size_t>(i)]);
        if (r > rate) rate = r, at = {i, j, k};
      }
    }
  if (err.empty() && dt > 0 && rate * dt > prm.cflMax) {
    err = fmt::format(
        "fluid step {}: CFL {:g} at cell ({}, {}, {}) (global index) exceeds fluid.cfl_max = {:g} "
        "(dt = {:g} s): reduce fluid.dt or use fluid.adaptive_dt",
        steps, rate * dt, dec.lo()[0] + at[0], dec.lo()[1] + at[1], dec.lo()[2] + at[2], prm.cflMax,
        dt);
  }
  // One allreduce for the check and the rates: the largest rate, change and speed, and whether
  // any rank failed (then every rank takes the error path of raiseIfAny). A failing rank arms
  // the failure deadline first, as raiseIfAny would before it waits.
  if (!err.empty()) noteLocalFailure(err, 3);
  double v[4] = {rate, du, umax, err.empty() ? 0.0 : 1.0};
  dec.comm().maxInPlace(std::span<double>(v, 4));
  if (v[3] > 0) dec.comm().raiseIfAny(err);
  maxRate = v[0];
  umaxLast = v[2];
  cflLast = v[0] * dt;
  if (dt > 0) steadyResidual = v[2] > 0 ? v[1] / v[2] : 0.0;
}
void FluidSolver::Impl::boundaryFluxes(double& in, double& out) const {
  // Volume fluxes eps_f u_n A through the physical faces of this block: into the box (in) and
  // out of it (out), signed, so in - out = d/dt int eps dV when continuity holds.
  in = out = 0;
  const Int3 n = dec.cells();
  for (int a = 0; a < 3; ++a) {
    const double area = dec.grid().cellVolume() / h[a];
    for (int s = 0; s < 2; ++s) {
      if (s == 0 ? !dec.atLowBoundary(a) : !dec.atHighBoundary(a)) continue;
      IndexBox b{{0, 0, 0}, n};
      b.lo[a] = s == 0 ? 0 : n[a];
      b.hi[a] = b.lo[a] + 1;
      const auto& U = f.u[a];
      double sum = 0;
      forEach(b, [&](int i, int j, int k) {
        const int ci = s == 0 ? i : i - (a == 0), cj = s == 0 ? j : j - (a == 1),
                  ck = s == 0 ? k : k - (a == 2);
        sum += f.eps(ci, cj, ck) * U(i, j, k) * area;  // boundary face eps = cell eps
      });
      if (s == 0)
        in += sum;
      else
        out += sum;
    }
  }
}

void FluidSolver::Impl::predictVelocity(double dt) {
  // u* = (eps^n u^n/dt + E + eps^{n+1} g + KUp) / (eps^{n+1}/dt + K) with the explicit terms
  // E = AB2 (or Euler) of H = -div(eps u u) + div(eps nu (grad u + grad u^T)), evaluated with
  // eps^n and u^n for all three components before any is updated.
  {
    ScopedPhase t(timers, Phase::FluidMomentum);
    massFluxes(f.u, f.epsOld, M);
    const bool useAb2 = prm.ab2 && haveOld;
    const double r = useAb2 ? dt / dtOld : 0.0;
    const double ca = useAb2 ? 1.0 + 0.5 * r : 1.0, cb = useAb2 ? -0.5 * r : 0.0;
    const double idt = 1.0 / dt;
    for (int c = 0; c < 3; ++c) explicitTerms(c, f.u, M, f.epsOld, mom, interiorFaces(c), Hn[c]);
    for (int c = 0; c < 3; ++c) {
      auto& U = f.u[c];
      auto& P = uPrev[c];
      PredictFaces pf;
      pf.c = c;
      pf.box = interiorFaces(c);
      pf.eps = &f.eps, pf.epsOld = &f.epsOld, pf.K = &f.K, pf.KUp = &f.KUp[c];
      pf.Hn = &Hn[c], pf.Ho = &Ho[c];
      pf.ca = ca, pf.cb = cb, pf.idt = idt, pf.g = prm.g[c];
      predictFaces(pf, U, P);
      predictBoxFaces(dec, bc, c, U, P);
    }
    std::swap(Hn, Ho);
  }
  // u* on the faces of the block's high side that belong to the neighbour (face n of a
  // periodic or interior block edge) enters div(eps u*).
  timers.syncPoint(dec.comm());
  ScopedPhase t(timers, Phase::FluidHalo);
  for (int c = 0; c < 3; ++c) faceHalo[c].gather(f.u[c], &timers, Exchange::IntraPhysics);
}

void FluidSolver::Impl::assemblePressureRhs(double dt) {
  // Row of cell P for q = p dt: sum_f w_f (q_P - q_nb) = -div(eps^{n+1} u*) - (eps^{n+1}-eps^n)/dt;
  // an outlet face moves its known q_b = p_out dt to the right-hand side.
  ScopedPhase t(timers, Phase::FluidPressureAssemble);
  if (coefficientsChanged || (anyK && dt != matrixDt) || matrixDt < 0) assembleMatrix(dt);
  const Int3 n = dec.cells();
  std::size_t r = 0;
  double sum = 0, dvol = 0, dvolGross = 0, scale2 = 0;
  Int3 badCell{-1, -1, -1};
  double badValue = 0;
  const double idt = 1.0 / dt;
  const bool warm = prm.warmStart;
  const double* en = f.eps.data().data();
  const double* eo = f.epsOld.data().data();
  // Row by row: the cells away from boundary faces through rhsRow (cell_rows.hpp), the
  // others cell by cell; then the sums over the row's cells, in cell order.
  double* const sc2 = rowWork.data();
  RhsRow row{};
  for (int a = 0; a < 3; ++a) {
    row.cellStride[a] = f.eps.stride(a);
    row.faceStride[a] = f.u[a].stride(a);
    row.h[a] = h[a];
  }
  row.idt = idt;
  row.dt = dt;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j) {
      const std::ptrdiff_t c0 = f.eps.index(0, j, k);
      const auto r0 = r;
      const auto cell = [&](int i) {  // one cell, with its boundary faces
        const std::ptrdiff_t c = c0 + i;
        double div = 0, flux = 0;
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          const auto& U = f.u[a];
          const std::ptrdiff_t s = f.eps.stride(a);
          const std::ptrdiff_t q = U.index(i, j, k), qs = U.stride(a);
          const double elo = 0.5 * (en[c - s] + en[c]), ehi = 0.5 * (en[c] + en[c + s]);
          div += (ehi * U.data()[q + qs] - elo * U.data()[q]) / h[a];
          flux += (std::fabs(ehi * U.data()[q + qs]) + std::fabs(elo * U.data()[q])) / h[a];
          for (int side = 0; side < 2; ++side) {
            const bool boundary = side == 0 ? (dec.atLowBoundary(a) && idx[a] == 0)
                                            : (dec.atHighBoundary(a) && idx[a] == n[a] - 1);
            if (!boundary) continue;
            const FaceBc& fb = bc.atLocal(dec, a, side, i, j, k);
            if (fb.type == BcType::Outlet)
              div -= outletWeight(en[c], f.K.data()[c], dt, h[a]) * fb.pressure * dt;
          }
        }
        const double de = en[c] - eo[c];
        rhs[r0 + static_cast<std::size_t>(i)] = -div - de * idt;
        const double sc = flux + std::fabs(de) * idt;
        sc2[i] = sc * sc;
        sol[r0 + static_cast<std::size_t>(i)] = warm ? f.p.data()[c] * dt : 0.0;
      };
      int i0 = 0, i1 = 0;
      interiorCells(j, k, i0, i1);
      for (int a = 0; a < 3; ++a) row.u[a] = f.u[a].data().data() + f.u[a].index(0, j, k);
      row.eps = en + c0;
      row.epsOld = eo + c0;
      row.p = warm ? f.p.data().data() + c0 : nullptr;
      rhsRow(row, i0, i1, rhs.data() + r0, sc2, sol.data() + r0);
      for (int i = 0; i < i0; ++i) cell(i);
      for (int i = i1; i < n[0]; ++i) cell(i);
      for (int i = 0; i < n[0]; ++i, ++r) {
        const std::ptrdiff_t c = c0 + i;
        if (!std::isfinite(rhs[r]) && badCell[0] < 0) {
          badCell = {dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k};
          badValue = rhs[r];
        }
        const double de = en[c] - eo[c];
        scale2 += sc2[i];
        dvol += de;
        dvolGross += std::fabs(de);
        sum += rhs[r];
      }
    }
  dVolLocal = dvol * dec.grid().cellVolume() / dt;
  dVolGrossLocal = dvolGross * dec.grid().cellVolume() / dt;
  rhsScaleLast = std::sqrt(dec.comm().sum(scale2));
  if (!std::isfinite(rhsScaleLast)) {
    // Every rank sees the non-finite global sum; the ranks that own a bad cell say where.
    std::string err;
    if (badCell[0] >= 0) {
      err = fmt::format(
          "fluid step {}: non-finite velocity after the predictor: divergence {:g} at cell ({}, "
          "{}, {}) (global index)",
          steps + 1, badValue, badCell[0], badCell[1], badCell[2]);
    }
    dec.comm().raiseIfAny(err);
    throw Error(fmt::format("fluid step {}: non-finite velocity", steps + 1));
  }
  if (singular) {
    // All faces Neumann or periodic: remove the (round-off, or physically inconsistent) mean.
    const double mean = dec.comm().sum(sum) / static_cast<double>(dec.grid().cellCount());
    for (auto& v : rhs) v -= mean;
  }
}

void FluidSolver::Impl::solvePressure() {
  ScopedPhase t(timers, Phase::FluidPressureSolve);
  const double scale = rhsScaleLast;
  itLast = ps->solve(rhs, sol, scale);
  if (!ps->lastConverged() && setupReuses > 0) {
    // A kept hierarchy that fell short: set up on this operator and solve on (every rank alike:
    // the verdict is global), so that every solve meets its tolerance as with a set-up each time.
    setUpPressure(matrixDt);
    itLast += ps->solve(rhs, sol, scale);
  }
  if (prm.reuse.on()) {
    if (setupIterations < 0)
      setupIterations = itLast;
    else if (itLast > std::max(static_cast<double>(setupIterations + 1),
                               prm.reuse.growth * static_cast<double>(setupIterations)))
      setupDue = true;
  }
  resLast = scale > 0 ? ps->lastResidualNorm() / scale : 0.0;
  itSum += itLast;
  ++solves;
  itMax = std::max(itMax, itLast);
  if (!ps->lastConverged()) {
    // The same verdict on every rank (hypre's norms are global).
    ++unconverged;
    if (ps->options().errorOnNoConvergence) {
      throw Error(fmt::format(
          "fluid.pressure.on_no_convergence = error: the pressure solve of fluid step {} did not "
          "converge: ||r|| = {:.3g} above the target {:.3g} after {} iterations "
          "(fluid.pressure.max_iter = {}, fluid.pressure.tol = {:g})",
          steps + 1, ps->lastResidualNorm(), ps->lastTarget(), itLast, ps->options().maxIter,
          ps->options().tol));
    }
  }
}

void FluidSolver::Impl::project(double dt) {
  const Int3 n = dec.cells();
  {
    ScopedPhase t(timers, Phase::FluidProject);
    std::size_t r = 0;
    double mean = 0;
    if (singular) {
      double s = 0;
      for (double v : sol) s += v;
      mean = dec.comm().sum(s) / static_cast<double>(dec.grid().cellCount());
    }
    const double idt = 1.0 / dt;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i, ++r) f.p(i, j, k) = (sol[r] - mean) * idt;
  }
  {
    ScopedPhase t(timers, Phase::FluidHalo);
    cellHalo.gather(f.p, &timers, Exchange::IntraPhysics);
  }
  ScopedPhase t(timers, Phase::FluidProject);
  const double* en = f.eps.data().data();
  const double* kk = f.K.data().data();
  const double* pp = f.p.data().data();
  for (int c = 0; c < 3; ++c) {
    auto& U = f.u[c];
    double* up = U.data().data();
    const std::ptrdiff_t cs = f.eps.stride(c);
    const double ih = dt / h[c];
    forFaces(U, f.eps, interiorFaces(c), [&](std::ptrdiff_t q, std::ptrdiff_t cc) {
      const double ef = 0.5 * (en[cc - cs] + en[cc]);
      const double kf = 0.5 * (kk[cc - cs] + kk[cc]);
      up[q] -= ef / (ef + kf * dt) * (pp[cc] - pp[cc - cs]) * ih;
    });
    projectOutletFaces(dec, bc, c, U, f.eps, f.K, f.p, dt, ih);
  }
  uGhostsFresh = false;
}

void FluidSolver::Impl::recordBalances() {
  boundaryFluxes(inLocal, outLocal);
  // Drag the fluid received this step (per unit fluid density, m^4/s^2): on every face that the
  // predictor advanced, V (KUp_f - K_f u_f^{n+1}) -- the semi-implicit drag is exactly implicit
  // in u^{n+1} once projected (A u^{n+1} = ... + K u_p - eps grad p).
  dragLocal = {0, 0, 0};
  if (!anyK) return;
  ScopedPhase t(timers, Phase::FluidProject);
  const double vol = dec.grid().cellVolume();
  for (int c = 0; c < 3; ++c) {
    const auto& U = f.u[c];
    const std::ptrdiff_t cs = f.eps.stride(c);
    const double* kk = f.K.data().data();
    const double* kup = f.KUp[c].data().data();
    const double* up = U.data().data();
    double sum = 0;
    forFaces(U, f.eps, interiorFaces(c), [&](std::ptrdiff_t q, std::ptrdiff_t cc) {
      sum += 0.5 * (kup[cc - cs] + kup[cc]) - 0.5 * (kk[cc - cs] + kk[cc]) * up[q];
    });
    dragLocal[c] = sum * vol;
  }
}

void FluidSolver::Impl::finishStep(double dt) {
  // eps^n <- eps^{n+1} (ghosts included: they are current).
  std::copy(f.eps.data().begin(), f.eps.data().end(), f.epsOld.data().begin());
  time += dt;
  ++steps;
  dtOld = dt;
  dtLast = dt;
  haveOld = true;
  computeRates(dt);
  ratesStale = false;
}

}  // namespace coloc::fv
