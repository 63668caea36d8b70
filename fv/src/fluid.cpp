// The fluid solver's construction, accessors, state and outputs (docs/fv.md); the step is in
// step.cpp, the choices are documented in docs/fv.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "cell_rows.hpp"
#include "fluid_impl.hpp"

namespace coloc::fv {

FluidSolver::Impl::Impl(const Decomposition& d, const Config& cfg, Timers& t)
    : dec(d), timers(t), bc(prm.bc) {
  // Setup time is booked by the caller (Timers phases must not nest).
  const auto& grid = dec.grid();
  // Checked on every rank's block, which every rank knows, so that every rank refuses together
  // (a check of its own block only would leave the others waiting in hypre).
  std::vector<Int3> boxLo, boxHi;
  dec.boxes(boxLo, boxHi);
  for (int a = 0; a < 3; ++a) {
    h[a] = grid.spacing(a);
    int smallest = dec.cells()[a];
    for (std::size_t r = 0; r < boxLo.size(); ++r)
      smallest = std::min(smallest, boxHi[r][a] - boxLo[r][a]);
    if (smallest < kGhost)
      throw ConfigError("partition.dims",
                        fmt::format("the fluid needs blocks of at least {} cells along every "
                                    "axis; a block has {} along axis {}: use fewer ranks along it",
                                    kGhost, smallest, a));
  }
  for (int a = 0; a < 3; ++a)
    if (grid.periodic[a] && grid.cells[a] < 3)
      throw ConfigError("domain.cells",
                        fmt::format("a periodic axis needs at least 3 cells for the pressure "
                                    "solver (hypre PFMG); axis {} has {}",
                                    "xyz"[a], grid.cells[a]));
  prm = fluidParams(cfg, grid);
  mom.nu = prm.nu;
  mom.h = h;
  mom.convection = prm.convection;
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
  if (prm.reuse.on()) {
    f.epsSetup = CellField(cl, 1.0);
    f.KSetup = CellField(cl, 0.0);
  }
  if (prm.heat.on) {
    f.T = CellField(cl, prm.heat.initial);
    f.heatSource = CellField(cl, 0.0);
    heatWork.assign(static_cast<std::size_t>(dec.ownedCellCount()), 0.0);
  }
  M = FaceField(dec, kGhost);
  uPrev = FaceField(dec, kGhost);
  for (int c = 0; c < 3; ++c) {
    Hn[c] = Field3<double>(faceLayout(dec, c, 0));
    Ho[c] = Field3<double>(faceLayout(dec, c, 0));
  }
  for (int c = 0; c < 3; ++c) f.u[c].fill(prm.initialVelocity[c]);
  const std::size_t n = static_cast<std::size_t>(dec.ownedCellCount());
  matrix.assign(7 * n, 0.0);
  rhs.assign(n, 0.0);
  sol.assign(n, 0.0);
  rowWork.assign(6 * static_cast<std::size_t>(dec.cells()[0]), 0.0);
  cellHalo = HaloPlan(dec, cl);
  for (int c = 0; c < 3; ++c) faceHalo[c] = HaloPlan(dec, f.u[c].layout());
  ps = std::make_unique<PressureSolver>(dec, prm.pressure);
  fillGhosts();
  // Warm the halo buffers for the largest field count (no allocation in the time loop).
  {
    Field3<double>* cells[6] = {&f.eps, &f.epsOld, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2]};
    cellHalo.gather(std::span<Field3<double>* const>(cells, 6));
  }
  computeRates(0.0);
}

FluidSolver::FluidSolver(const Decomposition& dec, const Config& cfg, Timers& timers)
    : impl_(std::make_unique<Impl>(dec, cfg, timers)) {}
FluidSolver::~FluidSolver() = default;

const FluidFields& FluidSolver::fields() const {
  return impl_->f;
}
bool FluidSolver::hasHeat() const {
  return impl_->prm.heat.on;
}
FluidFields& FluidSolver::edit() {
  auto& m = *impl_;
  m.uGhostsFresh = false;
  m.epsGhostsFresh = false;
  m.ratesStale = true;
  m.coefficientsChanged = true;
  m.tGhostsFresh = false;
  return m.f;
}
void FluidSolver::Impl::takeInputs(const CouplingInputs& in) {
  // The owned cells; the ghosts are filled by the step (exchangeInputs) or startCoupling().
  const IndexBox owned{{0, 0, 0}, dec.cells()};
  forEach(owned, [&](int i, int j, int k) {
    f.eps(i, j, k) = in.eps(i, j, k);
    f.K(i, j, k) = in.K(i, j, k);
    for (int d = 0; d < 3; ++d) f.KUp[d](i, j, k) = in.KUp[d](i, j, k);
  });
  if (in.heatSource && prm.heat.on)
    forEach(owned, [&](int i, int j, int k) { f.heatSource(i, j, k) = (*in.heatSource)(i, j, k); });
  heatImplicit = in.heatCoefficient && prm.heat.on;
  if (heatImplicit) {
    if (f.heatCoefficient.data().empty()) {  // the first step with convection
      f.heatCoefficient = CellField(f.T.layout(), 0.0);
      f.Tmean = CellField(f.T.layout(), 0.0);
    }
    forEach(owned, [&](int i, int j, int k) {
      f.heatCoefficient(i, j, k) = (*in.heatCoefficient)(i, j, k);
    });
  }
  uGhostsFresh = false;  // a superficial inlet's face velocity is U / eps
  epsGhostsFresh = false;
  ratesStale = true;
  coefficientsChanged = true;
}
void FluidSolver::startCoupling(const CouplingInputs& in) {
  auto& m = *impl_;
  auto& f = m.f;
  m.takeInputs(in);
  {
    ScopedPhase t(m.timers, Phase::FluidHalo);
    m.cellHalo.gather(f.eps, &m.timers, Exchange::IntraPhysics);
  }
  {
    ScopedPhase t(m.timers, Phase::FluidBoundary);
    applyScalarBc(m.dec, f.eps);
  }
  m.epsGhostsFresh = true;
  std::copy(f.eps.data().begin(), f.eps.data().end(), f.epsOld.data().begin());
}
void FluidSolver::step(double dt, const CouplingInputs& in) {
  impl_->takeInputs(in);
  impl_->step(dt);
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
  if (!m.prm.adaptive) return m.prm.dtFixed;
  if (m.ratesStale) {
    // The velocity was written through edit() since the last step: recompute the rate
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
  const double visc = m.prm.nu * (4.0 * s + 4.0 * mx);
  return std::min(m.prm.dtFixed, 1.0 / (m.maxRate / m.prm.cfl + visc));
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
  c.setups = m.setupsDone;
  c.setupDt = m.setupDt;
  c.matrixDt = m.matrixDt;
  c.setupReuses = m.setupReuses;
  c.setupIterations = m.setupIterations;
  c.setupDue = m.setupDue;
  c.itMax = m.itMax;
  c.itLast = m.itLast;
  c.unconverged = m.unconverged;
  c.haveOld = m.haveOld;
  c.ratesStale = m.ratesStale;
  c.heatEnthalpy0 = m.heatEnthalpy0;
  c.heatSource = m.heatSourceTotal;
  c.heatFace = m.heatFace;
  c.heatStarted = m.heatStarted;
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
  m.setupsDone = c.setups;
  m.itMax = static_cast<int>(c.itMax);
  m.itLast = static_cast<int>(c.itLast);
  m.unconverged = c.unconverged;  // kept by a re-balance and in checkpoints
  m.haveOld = c.haveOld;
  m.ratesStale = c.ratesStale;
  m.inLocal = m.outLocal = m.dVolLocal = m.dVolGrossLocal = 0;
  m.dragLocal = {0, 0, 0};
  m.heatEnthalpy0 = c.heatEnthalpy0;
  m.heatSourceTotal = c.heatSource;
  m.heatFace = c.heatFace;
  m.heatStarted = c.heatStarted;
  if (m.prm.heat.on) {
    m.cellHalo.gather(f.T);  // untimed, like the inputs above
    applyScalarBc(m.dec, f.T);
    m.tGhostsFresh = true;
  }
  m.restorePressure(c);
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
    const std::ptrdiff_t s = U.stride(c);
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
    const std::ptrdiff_t s = p.stride(c);
    const double ih = 1.0 / m.h[c];
    const bool lowB = m.dec.atLowBoundary(c), highB = m.dec.atHighBoundary(c);
    const double* pp = p.data().data();
    // a cell with a boundary face across c, cell by cell
    const auto cell = [&](int i, int j, int k) {
      const int idx = c == 0 ? i : c == 1 ? j : k;
      const std::ptrdiff_t q = p.index(i, j, k);
      auto faceGrad = [&](int face) -> double {
        // face: local face index along c (low face of cell `face`)
        if (face == 0 && lowB) {
          const FaceBc& fb = m.bc.atLocal(m.dec, c, 0, i, j, k);
          if (fb.type == BcType::Outlet)
            return outletDifference(0, pp[q - idx * s], fb.pressure) * 2.0 * ih;
          return n[c] > 1 ? (pp[q - (idx - 1) * s] - pp[q - idx * s]) * ih : 0.0;
        }
        if (face == n[c] && highB) {
          const std::ptrdiff_t last = q + (n[c] - 1 - idx) * s;
          const FaceBc& fb = m.bc.atLocal(m.dec, c, 1, i, j, k);
          if (fb.type == BcType::Outlet)
            return outletDifference(1, pp[last], fb.pressure) * 2.0 * ih;
          return n[c] > 1 ? (pp[last] - pp[last - s]) * ih : 0.0;
        }
        const std::ptrdiff_t r = q + (face - idx) * s;
        return (pp[r] - pp[r - s]) * ih;
      };
      out[c](i, j, k) = 0.5 * (faceGrad(idx) + faceGrad(idx + 1));
    };
    // the others row by row (cell_rows.hpp: the same arithmetic)
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j) {
        int i0 = 0, i1 = n[0];
        if (c == 0) {
          i0 = lowB ? 1 : 0;
          i1 = std::max(i0, highB ? n[0] - 1 : n[0]);
        } else {
          const int idx = c == 1 ? j : k;
          if ((lowB && idx == 0) || (highB && idx == n[c] - 1)) i0 = i1 = n[0];
        }
        gradientRow(pp + p.index(0, j, k), s, ih, i0, i1,
                    out[c].data().data() + out[c].index(0, j, k));
        for (int i = 0; i < i0; ++i) cell(i, j, k);
        for (int i = i1; i < n[0]; ++i) cell(i, j, k);
      }
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
                   {"setups", m.setupsDone},
                   {"setup_interval", m.prm.reuse.interval}};
  j["checks"] = {{"mass_balance", balance}};
  j["fluid"] = {{"steps", m.steps},
                {"unconverged_solves", m.unconverged},
                {"time", m.time},
                {"dt_last", m.dtLast},
                {"cfl_last", m.cflLast},
                {"steady_residual", m.steadyResidual},
                {"inflow", in},
                {"outflow", out},
                {"volume_rate", dvol},
                {"balance_scale", scale},
                {"drag_force", Json::array({v[3], v[4], v[5]})}};
  if (m.prm.heat.on) {
    // Energy balance: H - H0 = sum of the face heats + source heat, relative to the largest of
    // |H|, |H0|, the gross face heat and |source heat| (round-off of the enthalpy sum included).
    const double H = comm.sum(m.localEnthalpy(m.f.eps));
    const double H0 = m.heatStarted ? m.heatEnthalpy0 : H;
    double faces = 0, gross = 0;
    Json face;
    const char* names[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};
    for (std::size_t b = 0; b < 6; ++b) {
      faces += m.heatFace[b];
      gross += std::fabs(m.heatFace[b]);
      face[names[b]] = m.heatFace[b];
    }
    const double res = std::fabs(H - H0 - faces - m.heatSourceTotal);
    const double sc = std::max({std::fabs(H), std::fabs(H0), gross, std::fabs(m.heatSourceTotal)});
    j["checks"]["fluid_energy_balance"] = sc > 0 ? res / sc : (res > 0 ? 1.0 : 0.0);
    j["fluid_heat"] = {{"enthalpy", H},
                       {"enthalpy_initial", H0},
                       {"source_heat", m.heatSourceTotal},
                       {"face_heat", face},
                       {"substeps_last", m.heatSubstepsLast}};
  }
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
