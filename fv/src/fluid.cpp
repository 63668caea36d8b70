// The fluid step (SPEC section 1); the choices are documented in docs/fv.md.
#include "coloc/fv/fluid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "boundary.hpp"
#include "coloc/partition/halo.hpp"
#include "momentum.hpp"
#include "pressure_solver.hpp"

namespace coloc::fv {

namespace {
constexpr int kGhost = 2;

inline std::ptrdiff_t strideOf(const Field3<double>& f, int e) {
  return e == 0 ? 1 : e == 1 ? f.strideY() : f.strideZ();
}

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
}  // namespace

struct FluidSolver::Impl {
  const Decomposition& dec;
  Timers& timers;
  FluidFields f;
  // Parameters.
  double nu, dtFixed, cfl, cflMax, steadyTol;
  bool adaptive, ab2;
  Real3 g;  // gravity + body force (m/s^2)
  Real3 h;
  MomentumParams mom;
  BoxBc bc;
  bool singular = true;  // no Dirichlet pressure face: the pressure is defined up to a constant
  // Work arrays (allocated once).
  FaceField M;                           // mass fluxes eps_f u
  std::array<Field3<double>, 3> Hn, Ho;  // explicit terms at n and n-1
  FaceField uPrev;
  std::vector<double> matrix, rhs, sol;
  std::unique_ptr<PressureSolver> ps;
  HaloPlan cellHalo;
  std::array<HaloPlan, 3> faceHalo;
  // State.
  bool uGhostsFresh = false, coefficientsChanged = true, haveOld = false, ratesStale = false;
  // A superficial inlet reads eps in the ghost cells next to the face (U / eps of the adjacent
  // cell, tangential ghosts included): those ghosts must be current when the velocity ghosts are
  // filled, also when fields() was written outside a step (e.g. the coupling's set-up).
  bool superficialInlet = false, epsGhostsFresh = false;
  double time = 0, dtOld = 0, matrixDt = -1;
  bool anyK = false;
  long long steps = 0;
  long long itSum = 0, solves = 0;
  int itMax = 0, itLast = 0;
  double resLast = 0;
  double maxRate = 0;  // max over cells of sum_d |u_d|/h_d (1/s), after the last step
  double cflLast = 0, dtLast = 0, steadyResidual = std::numeric_limits<double>::infinity();
  double scale2 = 0, rhsScaleLast = 0;
  long long setupsOffset = 0;                       // pressure-matrix setups before a restore
  double inLocal = 0, outLocal = 0, dVolLocal = 0;  // last step, this rank
  double dVolGrossLocal = 0;  // sum over the cells of |d eps/dt| V_cell, last step, this rank
  double umaxLast = 0;        // max |u| over the faces after the last step (global)
  Real3 dragLocal{0, 0, 0};

  Impl(const Decomposition& d, const Config& cfg, Timers& t);
  IndexBox interiorFaces(int c) const {
    IndexBox b{{0, 0, 0}, dec.cells()};
    if (dec.atLowBoundary(c)) b.lo[c] = 1;
    return b;
  }
  void fillGhosts();
  void step(double dt);
  void assembleMatrix(double dt);
  void computeRates(double dt);
  void boundaryFluxes(double& in, double& out) const;
};

FluidSolver::Impl::Impl(const Decomposition& d, const Config& cfg, Timers& t) : dec(d), timers(t) {
  // Setup time is booked by the caller (Timers phases must not nest).
  const auto& grid = dec.grid();
  for (int a = 0; a < 3; ++a) {
    h[a] = grid.spacing(a);
    // Checked on every block's cuts, which every rank knows, so that every rank refuses
    // together (a check of its own block only would leave the others waiting in hypre).
    const auto& cuts = dec.cuts()[a];
    int smallest = dec.cells()[a];
    for (std::size_t c = 0; c + 1 < cuts.size(); ++c)
      smallest = std::min(smallest, cuts[c + 1] - cuts[c]);
    if (smallest < kGhost)
      throw ConfigError("partition.dims",
                        "the fluid needs blocks of at least " + std::to_string(kGhost) +
                            " cells along every axis; a block has " + std::to_string(smallest) +
                            " along axis " + std::to_string(a) + ": use fewer ranks along it");
  }
  for (int a = 0; a < 3; ++a)
    if (grid.periodic[a] && grid.cells[a] < 3)
      throw ConfigError("domain.cells",
                        std::string("a periodic axis needs at least 3 cells for the "
                                    "pressure solver (hypre PFMG); axis ") +
                            "xyz"[a] + " has " + std::to_string(grid.cells[a]));
  nu = cfg.number("fluid.nu");
  dtFixed = cfg.number("fluid.dt");
  adaptive = cfg.boolean("fluid.adaptive_dt");
  cfl = cfg.number("fluid.cfl");
  cflMax = cfg.number("fluid.cfl_max");
  steadyTol = cfg.number("fluid.steady_tol");
  ab2 = cfg.string("fluid.time_scheme") == "ab2";
  const auto gr = cfg.vec3("gravity");
  const auto bf = cfg.vec3("fluid.body_force");
  for (int a = 0; a < 3; ++a) g[a] = gr[a] + bf[a];
  mom.nu = nu;
  mom.h = h;
  mom.convection = cfg.string("fluid.convection") == "central" ? Convection::Central
                   : cfg.string("fluid.limiter") == "minmod"   ? Convection::Minmod
                                                               : Convection::VanLeer;
  bc = boundaryFromConfig(cfg, grid);
  singular = !bc.any(BcType::Outlet);
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s)
      if (bc.face[a][s].type == BcType::Inlet && bc.face[a][s].superficial) superficialInlet = true;
  for (const auto& p : bc.patch)
    if (p.type == BcType::Inlet && p.superficial) superficialInlet = true;

  const FieldLayout cl = cellLayout(dec, kGhost);
  f.u = FaceField(dec, kGhost);
  f.p = CellField(cl, 0.0);
  f.eps = CellField(cl, 1.0);
  f.epsOld = CellField(cl, 1.0);
  f.K = CellField(cl, 0.0);
  for (auto& k : f.KUp) k = CellField(cl, 0.0);
  M = FaceField(dec, kGhost);
  uPrev = FaceField(dec, kGhost);
  for (int c = 0; c < 3; ++c) {
    Hn[c] = Field3<double>(faceLayout(dec, c, 0));
    Ho[c] = Field3<double>(faceLayout(dec, c, 0));
  }
  const auto u0 = cfg.vec3("fluid.initial_velocity");
  for (int c = 0; c < 3; ++c) f.u[c].fill(u0[c]);
  const std::size_t n = static_cast<std::size_t>(dec.ownedCellCount());
  matrix.assign(7 * n, 0.0);
  rhs.assign(n, 0.0);
  sol.assign(n, 0.0);
  cellHalo = HaloPlan(dec, cl);
  for (int c = 0; c < 3; ++c) faceHalo[c] = HaloPlan(dec, f.u[c].layout());
  const std::string solver = cfg.string("fluid.pressure.solver");
  ps = std::make_unique<PressureSolver>(
      dec, solver == "smg" ? PressureSolver::Kind::Smg : PressureSolver::Kind::Pfmg,
      cfg.number("fluid.pressure.tol"), static_cast<int>(cfg.integer("fluid.pressure.max_iter")));
  fillGhosts();
  // Warm the halo buffers for the largest field count (no allocation in the time loop).
  {
    Field3<double>* cells[6] = {&f.eps, &f.epsOld, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2]};
    cellHalo.gather(std::span<Field3<double>* const>(cells, 6));
  }
  computeRates(0.0);
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
  {
    ScopedPhase t(timers, Phase::FluidHalo);
    for (int c = 0; c < 3; ++c) faceHalo[c].gather(f.u[c], &timers, Exchange::IntraPhysics);
  }
  ScopedPhase t(timers, Phase::FluidBoundary);
  for (int c = 0; c < 3; ++c) applyVelocityBc(dec, bc, c, f.u[c], &f.eps);
  uGhostsFresh = true;
}

void FluidSolver::Impl::assembleMatrix(double dt) {
  // Row of cell P: sum_f w_f (q_P - q_nb), w_f = eps_f^2 / ((eps_f + K_f dt) h_d^2), q = p dt.
  // An outlet face (Dirichlet p at the face, half a cell away) doubles w and moves the known
  // value to the right-hand side; inlet, wall and slip faces contribute nothing (dp/dn = 0).
  const Int3 n = dec.cells();
  const CellField& e = f.eps;
  const CellField& K = f.K;
  std::size_t r = 0;
  bool localK = false;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i, ++r) {
        double* row = &matrix[7 * r];
        double diag = 0;
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          const std::ptrdiff_t s = strideOf(e, a);
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
                w = 2.0 * ef * ef / ((ef + kf * dt) * h[a] * h[a]);
            }
            diag += w;
          }
        }
        row[0] = diag;
      }
  anyK = dec.comm().max(localK ? 1 : 0) == 1;  // the same rebuild decision on every rank
  ps->setMatrix(matrix);
  matrixDt = dt;
  coefficientsChanged = false;
}

void FluidSolver::Impl::computeRates(double dt) {
  // CFL per cell: dt sum_d max(|u_lo|,|u_hi|)/h_d; NaN/Inf anywhere stops the run; the steady
  // residual is max|u^{n+1}-u^n| / max|u^{n+1}|.
  const Int3 n = dec.cells();
  double rate = 0, du = 0, umax = 0;
  Int3 at{0, 0, 0};
  std::string err;
  for (int k = 0; k < n[2] && err.empty(); ++k)
    for (int j = 0; j < n[1] && err.empty(); ++j)
      for (int i = 0; i < n[0]; ++i) {
        double r = 0;
        for (int a = 0; a < 3; ++a) {
          const auto& U = f.u[a];
          const double lo = U(i, j, k);
          const double hi = U(i + (a == 0), j + (a == 1), k + (a == 2));
          if (!std::isfinite(lo) || !std::isfinite(hi)) {
            char buf[256];
            std::snprintf(buf, sizeof buf,
                          "fluid step %lld: non-finite velocity u_%c = %g at cell (%d, %d, %d) "
                          "(global index)",
                          steps, "xyz"[a], std::isfinite(lo) ? hi : lo, dec.lo()[0] + i,
                          dec.lo()[1] + j, dec.lo()[2] + k);
            err = buf;
            break;
          }
          r += std::max(std::fabs(lo), std::fabs(hi)) / h[a];
          umax = std::max(umax, std::fabs(lo));
          if (dt > 0) du = std::max(du, std::fabs(lo - uPrev[a](i, j, k)));
        }
        if (!err.empty()) break;
        if (r > rate) rate = r, at = {i, j, k};
      }
  if (err.empty() && dt > 0 && rate * dt > cflMax) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "fluid step %lld: CFL %g at cell (%d, %d, %d) (global index) exceeds "
                  "fluid.cfl_max = %g (dt = %g s): reduce fluid.dt or use fluid.adaptive_dt",
                  steps, rate * dt, dec.lo()[0] + at[0], dec.lo()[1] + at[1], dec.lo()[2] + at[2],
                  cflMax, dt);
    err = buf;
  }
  dec.comm().raiseIfAny(err);
  double v[3] = {rate, du, umax};
  dec.comm().maxInPlace(std::span<double>(v, 3));
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

void FluidSolver::Impl::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw Error("fluid step: invalid dt " + std::to_string(dt));
  const Int3 n = dec.cells();
  // 1. Halos of the cell inputs (eps^{n+1}, eps^n, K, K u_p) and of u^n; boundary ghosts.
  {
    ScopedPhase t(timers, Phase::FluidHalo);
    Field3<double>* cells[6] = {&f.eps, &f.epsOld, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2]};
    cellHalo.gather(std::span<Field3<double>* const>(cells, 6), &timers, Exchange::IntraPhysics);
  }
  {
    ScopedPhase t(timers, Phase::FluidBoundary);
    applyScalarBc(dec, f.eps);
    applyScalarBc(dec, f.epsOld);
    applyScalarBc(dec, f.K);
    for (auto& k : f.KUp) applyScalarBc(dec, k);
    epsGhostsFresh = true;
  }
  if (!uGhostsFresh) fillGhosts();

  // 2. Predictor: u* = (eps^n u^n/dt + E + eps^{n+1} g + KUp) / (eps^{n+1}/dt + K) with the
  //    explicit terms E = AB2 (or Euler) of H = -div(eps u u) + div(eps nu (grad u + grad u^T)),
  //    evaluated with eps^n.
  {
    ScopedPhase t(timers, Phase::FluidMomentum);
    massFluxes(f.u, f.epsOld, M);
    const bool useAb2 = ab2 && haveOld;
    const double r = useAb2 ? dt / dtOld : 0.0;
    const double ca = useAb2 ? 1.0 + 0.5 * r : 1.0, cb = useAb2 ? -0.5 * r : 0.0;
    const double idt = 1.0 / dt;
    // H of all three components from u^n first; then the in-place update of u.
    for (int c = 0; c < 3; ++c) explicitTerms(c, f.u, M, f.epsOld, mom, interiorFaces(c), Hn[c]);
    for (int c = 0; c < 3; ++c) {
      const IndexBox box = interiorFaces(c);
      auto& U = f.u[c];
      auto& P = uPrev[c];
      const std::ptrdiff_t cs = strideOf(f.eps, c);
      const double* en = f.eps.data().data();
      const double* eo = f.epsOld.data().data();
      const double* kk = f.K.data().data();
      const double* kup = f.KUp[c].data().data();
      double* up = U.data().data();
      double* pp = P.data().data();
      const double* hn = Hn[c].data().data();
      const double* ho = Ho[c].data().data();
      const double gc = g[c];
      for (int k = box.lo[2]; k < box.hi[2]; ++k)
        for (int j = box.lo[1]; j < box.hi[1]; ++j) {
          const std::ptrdiff_t q0 = U.index(box.lo[0], j, k), c0 = f.eps.index(box.lo[0], j, k),
                               h0 = Hn[c].index(box.lo[0], j, k);
          for (int i = 0; i < box.hi[0] - box.lo[0]; ++i) {
            const std::ptrdiff_t q = q0 + i, cc = c0 + i, hh = h0 + i;
            const double efn = 0.5 * (en[cc - cs] + en[cc]);
            const double efo = 0.5 * (eo[cc - cs] + eo[cc]);
            const double kf = 0.5 * (kk[cc - cs] + kk[cc]);
            const double kupf = 0.5 * (kup[cc - cs] + kup[cc]);
            const double E = ca * hn[hh] + cb * ho[hh];
            pp[q] = up[q];
            up[q] = (efo * up[q] * idt + E + efn * gc + kupf) / (efn * idt + kf);
          }
        }
      // Boundary faces keep u^n (Dirichlet) for uPrev too.
      // Outlet faces: du/dn = 0 on the predicted velocity.
      for (int s = 0; s < 2; ++s) {
        if (s == 0 ? !dec.atLowBoundary(c) : !dec.atHighBoundary(c)) continue;
        IndexBox b{{0, 0, 0}, n};
        b.lo[c] = s == 0 ? 0 : n[c];
        b.hi[c] = b.lo[c] + 1;
        const std::ptrdiff_t sh = s == 0 ? strideOf(U, c) : -strideOf(U, c);
        forEach(b, [&](int i, int j, int k) {
          const std::ptrdiff_t q = U.index(i, j, k);
          pp[q] = up[q];
          if (bc.atLocal(dec, c, s, i, j, k).type == BcType::Outlet) up[q] = up[q + sh];
        });
      }
    }
    std::swap(Hn, Ho);
  }
  {
    // u* on the faces of the block's high side that belong to the neighbour (face n of a
    // periodic or interior block edge) enters div(eps u*).
    ScopedPhase t(timers, Phase::FluidHalo);
    for (int c = 0; c < 3; ++c) faceHalo[c].gather(f.u[c], &timers, Exchange::IntraPhysics);
  }

  // 3. Pressure equation for q = p dt: sum_f w_f (q_P - q_nb) = -div(eps^{n+1} u*) -
  // (eps^{n+1}-eps^n)/dt.
  {
    ScopedPhase t(timers, Phase::FluidPressureAssemble);
    if (coefficientsChanged || (anyK && dt != matrixDt) || matrixDt < 0) assembleMatrix(dt);
    std::size_t r = 0;
    double sum = 0, dvol = 0, dvolGross = 0;
    scale2 = 0;
    Int3 badCell{-1, -1, -1};
    double badValue = 0;
    const double idt = 1.0 / dt;
    const double* en = f.eps.data().data();
    const double* eo = f.epsOld.data().data();
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i, ++r) {
          const std::ptrdiff_t c = f.eps.index(i, j, k);
          double div = 0, flux = 0;
          const int idx[3] = {i, j, k};
          for (int a = 0; a < 3; ++a) {
            const auto& U = f.u[a];
            const std::ptrdiff_t s = strideOf(f.eps, a);
            const std::ptrdiff_t q = U.index(i, j, k), qs = strideOf(U, a);
            const double elo = 0.5 * (en[c - s] + en[c]), ehi = 0.5 * (en[c] + en[c + s]);
            div += (ehi * U.data()[q + qs] - elo * U.data()[q]) / h[a];
            flux += (std::fabs(ehi * U.data()[q + qs]) + std::fabs(elo * U.data()[q])) / h[a];
            // Outlet: known face value q_b = p_out dt on the right-hand side.
            for (int side = 0; side < 2; ++side) {
              const bool boundary = side == 0 ? (dec.atLowBoundary(a) && idx[a] == 0)
                                              : (dec.atHighBoundary(a) && idx[a] == n[a] - 1);
              if (!boundary) continue;
              const FaceBc& fb = bc.atLocal(dec, a, side, i, j, k);
              if (fb.type == BcType::Outlet) {
                const double ef = en[c], kf = f.K.data()[c];
                div -= 2.0 * ef * ef / ((ef + kf * dt) * h[a] * h[a]) * fb.pressure * dt;
              }
            }
          }
          const double de = en[c] - eo[c];
          rhs[r] = -div - de * idt;
          if (!std::isfinite(rhs[r]) && badCell[0] < 0) {
            badCell = {dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k};
            badValue = rhs[r];
          }
          const double sc = flux + std::fabs(de) * idt;
          scale2 += sc * sc;
          dvol += de;
          dvolGross += std::fabs(de);
          sum += rhs[r];
          sol[r] = f.p.data()[c] * dt;  // warm start
        }
    dVolLocal = dvol * dec.grid().cellVolume() / dt;
    dVolGrossLocal = dvolGross * dec.grid().cellVolume() / dt;
    rhsScaleLast = std::sqrt(dec.comm().sum(scale2));
    if (!std::isfinite(rhsScaleLast)) {
      // Every rank sees the non-finite global sum; the ranks that own a bad cell say where.
      std::string err;
      if (badCell[0] >= 0) {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "fluid step %lld: non-finite velocity after the predictor: divergence %g at "
                      "cell (%d, %d, %d) (global index)",
                      steps + 1, badValue, badCell[0], badCell[1], badCell[2]);
        err = buf;
      }
      dec.comm().raiseIfAny(err);
      throw Error("fluid step " + std::to_string(steps + 1) + ": non-finite velocity");
    }
    if (singular) {
      // All faces Neumann or periodic: remove the (round-off, or physically inconsistent) mean.
      const double mean = dec.comm().sum(sum) / static_cast<double>(dec.grid().cellCount());
      for (auto& v : rhs) v -= mean;
    }
  }
  {
    ScopedPhase t(timers, Phase::FluidPressureSolve);
    const double scale = rhsScaleLast;
    itLast = ps->solve(rhs, sol, scale);
    resLast = scale > 0 ? ps->lastResidualNorm() / scale : 0.0;
    itSum += itLast;
    ++solves;
    itMax = std::max(itMax, itLast);
  }

  // 4. Projection: u^{n+1} = u* - eps_f/(eps_f + K_f dt) (q_R - q_L)/h.
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
  {
    ScopedPhase t(timers, Phase::FluidProject);
    const double* en = f.eps.data().data();
    const double* kk = f.K.data().data();
    const double* pp = f.p.data().data();
    for (int c = 0; c < 3; ++c) {
      auto& U = f.u[c];
      double* up = U.data().data();
      const std::ptrdiff_t cs = strideOf(f.eps, c);
      const double ih = dt / h[c];
      forFaces(U, f.eps, interiorFaces(c), [&](std::ptrdiff_t q, std::ptrdiff_t cc) {
        const double ef = 0.5 * (en[cc - cs] + en[cc]);
        const double kf = 0.5 * (kk[cc - cs] + kk[cc]);
        up[q] -= ef / (ef + kf * dt) * (pp[cc] - pp[cc - cs]) * ih;
      });
      for (int s = 0; s < 2; ++s) {
        if (s == 0 ? !dec.atLowBoundary(c) : !dec.atHighBoundary(c)) continue;
        if (!bc.anyOnFace(c, s, BcType::Outlet)) continue;
        IndexBox b{{0, 0, 0}, n};
        b.lo[c] = s == 0 ? 0 : n[c];
        b.hi[c] = b.lo[c] + 1;
        forEach(b, [&](int i, int j, int k) {
          const FaceBc& fb = bc.atLocal(dec, c, s, i, j, k);
          if (fb.type != BcType::Outlet) return;
          const double pb = fb.pressure;
          const std::ptrdiff_t q = U.index(i, j, k);
          const std::ptrdiff_t cc = s == 0 ? f.eps.index(i, j, k) : f.eps.index(i, j, k) - cs;
          const double ef = en[cc], kf = kk[cc];
          const double grad = s == 0 ? (pp[cc] - pb) : (pb - pp[cc]);
          up[q] -= ef / (ef + kf * dt) * grad * 2.0 * ih;
        });
      }
    }
    uGhostsFresh = false;
  }
  boundaryFluxes(inLocal, outLocal);
  // Drag the fluid received this step (per unit fluid density, m^4/s^2): on every face that the
  // predictor advanced, V (KUp_f - K_f u_f^{n+1}) -- the semi-implicit drag is exactly implicit
  // in u^{n+1} once projected (A u^{n+1} = ... + K u_p - eps grad p).
  dragLocal = {0, 0, 0};
  if (anyK) {
    ScopedPhase t(timers, Phase::FluidProject);
    const double vol = dec.grid().cellVolume();
    for (int c = 0; c < 3; ++c) {
      const auto& U = f.u[c];
      const std::ptrdiff_t cs = strideOf(f.eps, c);
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

FluidSolver::FluidSolver(const Decomposition& dec, const Config& cfg, Timers& timers)
    : impl_(std::make_unique<Impl>(dec, cfg, timers)) {}
FluidSolver::~FluidSolver() = default;

FluidFields& FluidSolver::fields() {
  impl_->uGhostsFresh = false;
  impl_->epsGhostsFresh = false;
  impl_->ratesStale = true;
  return impl_->f;
}
const FluidFields& FluidSolver::fields() const {
  return impl_->f;
}
void FluidSolver::markCoefficientsChanged() {
  impl_->coefficientsChanged = true;
}
void FluidSolver::step(double dt) {
  impl_->step(dt);
}
void FluidSolver::syncEpsOld() {
  auto& f = impl_->f;
  std::copy(f.eps.data().begin(), f.eps.data().end(), f.epsOld.data().begin());
}
double FluidSolver::time() const {
  return impl_->time;
}
double FluidSolver::steadyResidual() const {
  return impl_->steadyResidual;
}
long long FluidSolver::stepCount() const {
  return impl_->steps;
}

double FluidSolver::nextDt() const {
  auto& m = *impl_;
  if (!m.adaptive) return m.dtFixed;
  if (m.ratesStale) {
    // The velocity was written through fields() since the last step: recompute the rate
    // (collective, like step()).
    m.computeRates(0.0);
    m.ratesStale = false;
  }
  // Explicit terms: convective rate R = max sum_d |u_d|/h_d (CFL = R dt) and viscous rate
  // V = nu (4 sum 1/h^2 + 4 max 1/h^2) (largest eigenvalue of the full-stress operator). The two
  // add in the Adams-Bashforth stability region, so dt = 1 / (R/cfl + V): the CFL target is met
  // when convection dominates and |V dt| < 1 (AB2's real-axis limit) always.
  double s = 0, mx = 0;
  for (int a = 0; a < 3; ++a) {
    s += 1.0 / (m.h[a] * m.h[a]);
    mx = std::max(mx, 1.0 / (m.h[a] * m.h[a]));
  }
  const double visc = m.nu * (4.0 * s + 4.0 * mx);
  return std::min(m.dtFixed, 1.0 / (m.maxRate / m.cfl + visc));
}

FluidCounters FluidSolver::counters() const {
  const auto& m = *impl_;
  FluidCounters c;
  c.time = m.time;
  c.dtOld = m.dtOld;
  c.dtLast = m.dtLast;
  c.cflLast = m.cflLast;
  c.maxRate = m.maxRate;
  c.steadyResidual = m.steadyResidual;
  c.resLast = m.resLast;
  c.rhsScaleLast = m.rhsScaleLast;
  c.steps = m.steps;
  c.itSum = m.itSum;
  c.solves = m.solves;
  c.setups = m.ps->setups() + m.setupsOffset;
  c.itMax = m.itMax;
  c.itLast = m.itLast;
  c.haveOld = m.haveOld;
  c.ratesStale = m.ratesStale;
  return c;
}

const std::array<Field3<double>, 3>& FluidSolver::history() const {
  return impl_->Ho;  // step() swaps Hn and Ho at its end: Ho holds the last step's terms
}
std::array<Field3<double>, 3>& FluidSolver::history() {
  return impl_->Ho;
}

void FluidSolver::restoreState(const FluidCounters& c) {
  auto& m = *impl_;
  auto& f = m.f;
  // Ghosts as a step leaves them: the cell inputs gathered and closed by the boundary
  // conditions, p gathered (its box-face ghosts are never read), u refreshed on demand.
  {
    Field3<double>* cells[7] = {&f.eps, &f.epsOld, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2], &f.p};
    m.cellHalo.gather(std::span<Field3<double>* const>(cells, 7));
  }
  applyScalarBc(m.dec, f.eps);
  applyScalarBc(m.dec, f.epsOld);
  applyScalarBc(m.dec, f.K);
  for (auto& k : f.KUp) applyScalarBc(m.dec, k);
  m.uGhostsFresh = false;
  m.epsGhostsFresh = true;  // gathered and closed above
  m.coefficientsChanged = true;
  m.matrixDt = -1;
  m.time = c.time;
  m.dtOld = c.dtOld;
  m.dtLast = c.dtLast;
  m.cflLast = c.cflLast;
  m.maxRate = c.maxRate;
  m.steadyResidual = c.steadyResidual;
  m.resLast = c.resLast;
  m.rhsScaleLast = c.rhsScaleLast;
  m.steps = c.steps;
  m.itSum = c.itSum;
  m.solves = c.solves;
  m.setupsOffset = c.setups - m.ps->setups();
  m.itMax = static_cast<int>(c.itMax);
  m.itLast = static_cast<int>(c.itLast);
  m.haveOld = c.haveOld;
  m.ratesStale = c.ratesStale;
  m.inLocal = m.outLocal = m.dVolLocal = m.dVolGrossLocal = 0;
  m.dragLocal = {0, 0, 0};
}

void FluidSolver::cellVelocity(std::array<CellField, 3>& out) {
  auto& m = *impl_;
  if (!m.uGhostsFresh) m.fillGhosts();
  const FieldLayout cl = cellLayout(m.dec, kGhost);
  for (int c = 0; c < 3; ++c) {
    if (!(out[c].layout() == cl)) out[c] = CellField(cl);
    const auto& U = m.f.u[c];
    IndexBox b = cl.allocated();
    for (int a = 0; a < 3; ++a) b.lo[a] += kGhost - 1, b.hi[a] -= kGhost - 1;  // one ghost layer
    const std::ptrdiff_t s = strideOf(U, c);
    forFaces(U, out[c], b, [&](std::ptrdiff_t q, std::ptrdiff_t cc) {
      out[c].data()[cc] = 0.5 * (U.data()[q] + U.data()[q + s]);
    });
  }
}

void FluidSolver::pressureGradient(std::array<CellField, 3>& out) {
  // Face gradients (p_R - p_L)/h; at an outlet face (p_b - p_in)/(h/2); at a Neumann face (inlet,
  // wall, slip) the gradient of the next interior face (the projection does not define it there,
  // and hydrostatic pressure must reach the particles next to a wall). Cell value: mean of its
  // two faces. One ghost layer: halo, then zero-gradient at the box faces.
  auto& m = *impl_;
  const FieldLayout cl = cellLayout(m.dec, kGhost);
  const Int3 n = m.dec.cells();
  const CellField& p = m.f.p;
  for (int c = 0; c < 3; ++c) {
    if (!(out[c].layout() == cl)) out[c] = CellField(cl);
    const std::ptrdiff_t s = strideOf(p, c);
    const double ih = 1.0 / m.h[c];
    const bool lowB = m.dec.atLowBoundary(c), highB = m.dec.atHighBoundary(c);
    forEach(IndexBox{{0, 0, 0}, n}, [&](int i, int j, int k) {
      const int idx = c == 0 ? i : c == 1 ? j : k;
      const std::ptrdiff_t q = p.index(i, j, k);
      const double* pp = p.data().data();
      auto faceGrad = [&](int face) -> double {
        // face: local face index along c (low face of cell `face`)
        if (face == 0 && lowB) {
          const FaceBc& fb = m.bc.atLocal(m.dec, c, 0, i, j, k);
          if (fb.type == BcType::Outlet) return (pp[q - (idx - face) * s] - fb.pressure) * 2.0 * ih;
          return n[c] > 1 ? (pp[q - (idx - 1) * s] - pp[q - idx * s]) * ih : 0.0;
        }
        if (face == n[c] && highB) {
          const std::ptrdiff_t last = q + (n[c] - 1 - idx) * s;
          const FaceBc& fb = m.bc.atLocal(m.dec, c, 1, i, j, k);
          if (fb.type == BcType::Outlet) return (fb.pressure - pp[last]) * 2.0 * ih;
          return n[c] > 1 ? (pp[last] - pp[last - s]) * ih : 0.0;
        }
        const std::ptrdiff_t r = q + (face - idx) * s;
        return (pp[r] - pp[r - s]) * ih;
      };
      out[c](i, j, k) = 0.5 * (faceGrad(idx) + faceGrad(idx + 1));
    });
  }
  {
    ScopedPhase t(m.timers, Phase::FluidHalo);
    Field3<double>* fs[3] = {&out[0], &out[1], &out[2]};
    m.cellHalo.gather(std::span<Field3<double>* const>(fs, 3), &m.timers, Exchange::IntraPhysics);
  }
  for (auto& o : out) applyScalarBc(m.dec, o);
}

Json FluidSolver::diagnostics() const {
  const auto& m = *impl_;
  const Comm& comm = m.dec.comm();
  double v[7] = {m.inLocal,      m.outLocal,     m.dVolLocal,     m.dragLocal[0],
                 m.dragLocal[1], m.dragLocal[2], m.dVolGrossLocal};
  comm.sumInPlace(std::span<double>(v, 7));
  const double in = v[0], out = v[1], dvol = v[2];
  // Physical scale of the volume balance (m^3/s): the largest of the fluxes through the
  // boundary, the gross rate of change of the fluid volume (sum over the cells of
  // |d eps/dt| V_cell) and max|u| times the largest cell-face area (the flux through the
  // fastest face). A closed box (in = out = 0, dV round-off) then reports round-off, not
  // |dV|/|dV| = 1.
  const double vol = m.dec.grid().cellVolume();
  const double areaMax = std::max({vol / m.h[0], vol / m.h[1], vol / m.h[2]});
  const double scale = std::max({std::fabs(in), std::fabs(out), v[6], m.umaxLast * areaMax});
  const double residual = std::fabs(in - out - dvol);
  const double balance = scale > 0 ? residual / scale : (residual > 0 ? 1.0 : 0.0);
  Json j;
  j["pressure"] = {{"iterations_avg", m.solves ? static_cast<double>(m.itSum) / m.solves : 0.0},
                   {"iterations_max", m.itMax},
                   {"iterations_last", m.itLast},
                   {"residual_last", m.resLast},
                   {"rhs_scale_last", m.rhsScaleLast},
                   {"setups", m.ps->setups() + m.setupsOffset}};
  j["checks"] = {{"mass_balance", balance}};
  j["fluid"] = {{"steps", m.steps},
                {"time", m.time},
                {"dt_last", m.dtLast},
                {"cfl_last", m.cflLast},
                {"steady_residual", m.steadyResidual},
                {"inflow", in},
                {"outflow", out},
                {"volume_rate", dvol},
                {"balance_scale", scale},
                {"drag_force", Json::array({v[3], v[4], v[5]})}};
  return j;
}

Json runFluidOnly(FluidSolver& solver, const Config& cfg) {
  const long long steps = cfg.integer("run.steps");
  const double endTime = cfg.number("run.end_time");
  const double steadyTol = cfg.number("fluid.steady_tol");
  const double t0 = MPI_Wtime();
  long long n = 0;
  std::string stop = steps > 0 ? "steps" : "end_time";
  while (steps > 0 ? n < steps : solver.time() < endTime * (1 - 1e-12)) {
    double dt = solver.nextDt();
    if (steps == 0) dt = std::min(dt, endTime - solver.time());
    solver.step(dt);
    ++n;
    if (steadyTol > 0 && solver.steadyResidual() < steadyTol) {
      stop = "steady";
      break;
    }
  }
  Json j;
  j["steps"] = n;
  j["sim_time"] = solver.time();
  j["stop"] = stop;
  j["wall_s"] = MPI_Wtime() - t0;
  return j;
}

}  // namespace coloc::fv
