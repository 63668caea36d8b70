// The fluid energy equation (fluid.heat; docs/heat.md, "Fluid energy"):
//
//   d(rho_f c_f eps T)/dt + div(rho_f c_f eps u T) = div(eps k_f grad T) + S
//
// conservative finite volumes on the fluid's cells, explicit (forward Euler) with sub-steps,
// first-order upwind advection with the face volume fluxes eps_f u_f A of the projected
// velocity (the fluxes of the continuity equation), central diffusion. Every face flux is
// computed from the same operands by the two cells that share it, so it cancels exactly; the
// heat through the box faces and from the source is accumulated (J) for the energy balance.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "coloc/core/failure.hpp"
#include "fluid_impl.hpp"

namespace coloc::fv {

double FluidSolver::Impl::heatFluxes(const double* T, int i, int j, int k, double* bnd,
                                     double& rate) const {
  // Heat into owned cell (i, j, k) per rho_f c_f (K m^3/s) through its six faces; the box faces
  // add theirs to bnd[2 a + side] too. rate += sum_f |F_f| + D_f (m^3/s).
  const Int3 n = dec.cells();
  const double* e = f.eps.data().data();
  const double alpha = prm.heat.conductivity / (prm.heat.rho * prm.heat.capacity);
  const double vol = dec.grid().cellVolume();
  const std::ptrdiff_t c = f.T.index(i, j, k);
  const int idx[3] = {i, j, k};
  double q = 0;
  for (int a = 0; a < 3; ++a) {
    const double area = vol / h[a];
    const double dcoef = alpha * area / h[a];
    const std::ptrdiff_t s = f.T.stride(a);
    const auto& U = f.u[a];
    const std::ptrdiff_t q0 = U.index(i, j, k), qs = U.stride(a);
    for (int side = 0; side < 2; ++side) {
      const bool boundary = side == 0 ? (dec.atLowBoundary(a) && idx[a] == 0)
                                      : (dec.atHighBoundary(a) && idx[a] == n[a] - 1);
      const double un = U.data()[side == 0 ? q0 : q0 + qs];
      if (!boundary) {
        const std::ptrdiff_t nb = side == 0 ? c - s : c + s;
        const double ef = 0.5 * (e[c] + e[nb]);
        const double F = ef * un * area;  // volume flux along +a
        const std::ptrdiff_t lower = side == 0 ? nb : c, upper = side == 0 ? c : nb;
        const double adv = F * (F >= 0 ? T[lower] : T[upper]);
        const double dif = dcoef * ef * (T[nb] - T[c]);
        q += (side == 0 ? adv : -adv) + dif;
        rate += std::fabs(F) + dcoef * ef;
        continue;
      }
      const FaceBc& fb = bc.atLocal(dec, a, side, i, j, k);
      const double ec = e[c];
      double qf = 0;
      if (fb.type == BcType::Inlet || fb.type == BcType::Outlet) {
        const double F = ec * un * area;
        const bool inflow = side == 0 ? F > 0 : F < 0;
        // Inlet: the inflow carries the inlet temperature, which is also the face's Dirichlet
        // value for conduction. Outlet: zero gradient (the cell's temperature leaves).
        const double Tb = fb.type == BcType::Inlet && inflow ? fb.temperature : T[c];
        qf = side == 0 ? F * Tb : -F * Tb;
        rate += std::fabs(F);
        if (fb.type == BcType::Inlet) {
          qf += 2.0 * dcoef * ec * (fb.temperature - T[c]);
          rate += 2.0 * dcoef * ec;
        }
      } else if (fb.fixedTemperature) {
        // Wall or slip at a fixed temperature, half a cell from the centre; else adiabatic.
        qf = 2.0 * dcoef * ec * (fb.temperature - T[c]);
        rate += 2.0 * dcoef * ec;
      }
      bnd[2 * a + side] += qf;
      q += qf;
    }
  }
  return q;
}

double FluidSolver::Impl::localEnthalpy(const CellField& eps) const {
  double sum = 0;
  forEach(IndexBox{{0, 0, 0}, dec.cells()},
          [&](int i, int j, int k) { sum += eps(i, j, k) * f.T(i, j, k); });
  return prm.heat.rho * prm.heat.capacity * dec.grid().cellVolume() * sum;
}

void FluidSolver::Impl::refreshTemperatureGhosts() {
  {
    ScopedPhase t(timers, Phase::FluidHalo);
    cellHalo.gather(f.T, &timers, Exchange::IntraPhysics);
  }
  ScopedPhase t(timers, Phase::FluidBoundary);
  applyScalarBc(dec, f.T);
  tGhostsFresh = true;
}

void FluidSolver::Impl::heatStep(double dt) {
  if (!tGhostsFresh) refreshTemperatureGhosts();
  // The projected velocity on every face of the owned cells: the high faces of an interior
  // block edge belong to the neighbour (its u^{n+1} arrives by the halo).
  if (!uGhostsFresh) fillGhosts();
  if (!heatStarted) {
    // The state at the start of the first step: eps^n (eps may already hold eps^{n+1}).
    heatEnthalpy0 = dec.comm().sum(localEnthalpy(f.epsOld));
    heatStarted = true;
  }
  // Timed as FluidMomentum (the fluid's explicit transport terms) and FluidHalo.
  std::optional<ScopedPhase> phase(std::in_place, timers, Phase::FluidMomentum);
  const Int3 n = dec.cells();
  const double vol = dec.grid().cellVolume();
  const double rc = prm.heat.rho * prm.heat.capacity;
  const double* T = f.T.data().data();
  const double* en = f.eps.data().data();
  const double* eo = f.epsOld.data().data();
  // Sub-steps: the explicit update is a convex combination of the old values (no new extrema)
  // when dt_sub (sum_f |F_f| + D_f) <= min(eps^n, eps^{n+1}) V in every cell.
  double ratio = 0;
  {
    double bnd[6] = {0, 0, 0, 0, 0, 0};
    std::size_t r = 0;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i, ++r) {
          double rate = 0;
          (void)heatFluxes(T, i, j, k, bnd, rate);
          const std::ptrdiff_t c = f.T.index(i, j, k);
          ratio = std::max(ratio, rate / (std::min(en[c], eo[c]) * vol));
        }
  }
  ratio = dec.comm().max(ratio);
  // The sub-steps' positivity bound: dt_sub <= min(eps^n, eps^{n+1}) V / (sum_f |F_f| + D_f).
  const double want = std::ceil(dt * ratio);
  if (!std::isfinite(want) || want > static_cast<double>(kMaxHeatSubsteps))
    throw Error(
        fmt::format("fluid step {}: the energy equation would need {:.3g} sub-steps of the "
                    "step's dt = {:.4g} s (more than {}; the face flows and the conduction "
                    "through the cells, fluid.conductivity = {:g} W/(m K)): reduce fluid.dt, or "
                    "the velocities",
                    steps + 1, want, dt, kMaxHeatSubsteps, prm.heat.conductivity));
  const long long N = std::max(1LL, static_cast<long long>(want));
  const double dts = dt / static_cast<double>(N);
  const bool hasSource = !f.heatSource.data().empty();
  // Convection: the particles' exchange point-implicit in T (CouplingInputs::heatCoefficient):
  // the cell receives S - K T^m at sub-step m; Tmean collects the mean of T^m for the particles.
  const bool implicit = heatImplicit;
  double* Tbar = implicit ? f.Tmean.data().data() : nullptr;
  const double* Kh = implicit ? f.heatCoefficient.data().data() : nullptr;
  if (implicit) f.Tmean.fill(0.0);
  const double share = 1.0 / static_cast<double>(N);
  double stepBnd[6] = {0, 0, 0, 0, 0, 0};
  double stepSource = 0;
  const auto epsAt = [&](std::ptrdiff_t c, long long m) {
    if (m == 0) return eo[c];
    if (m == N) return en[c];
    return eo[c] + (static_cast<double>(m) / static_cast<double>(N)) * (en[c] - eo[c]);
  };
  for (long long m = 1; m <= N; ++m) {
    double bnd[6] = {0, 0, 0, 0, 0, 0};
    double src = 0;
    std::size_t r = 0;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i, ++r) {
          double rate = 0;
          double q = heatFluxes(T, i, j, k, bnd, rate);
          if (hasSource) {
            const double s = f.heatSource(i, j, k);
            src += s;
            q += s / rc;
          }
          heatWork[r] = q;
        }
    r = 0;
    double* Tw = f.T.data().data();
    if (implicit) {
      for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
          for (int i = 0; i < n[0]; ++i, ++r) {
            const std::ptrdiff_t c = f.T.index(i, j, k);
            Tw[c] = (epsAt(c, m - 1) * Tw[c] + dts / vol * heatWork[r]) /
                    (epsAt(c, m) + dts / vol * Kh[c] / rc);
            src -= Kh[c] * Tw[c];
            Tbar[c] += share * Tw[c];
          }
    } else {
      for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
          for (int i = 0; i < n[0]; ++i, ++r) {
            const std::ptrdiff_t c = f.T.index(i, j, k);
            Tw[c] = (epsAt(c, m - 1) * Tw[c] + dts / vol * heatWork[r]) / epsAt(c, m);
          }
    }
    for (int b = 0; b < 6; ++b) stepBnd[b] += rc * dts * bnd[b];
    stepSource += dts * src;
    phase.reset();
    {
      ScopedPhase th(timers, Phase::FluidHalo);
      cellHalo.gather(f.T, &timers, Exchange::IntraPhysics);
    }
    phase.emplace(timers, Phase::FluidMomentum);
  }
  if (implicit) {
    // The mean's ghosts across block faces and periodic faces (the coupling samples it; at the
    // box faces it mirrors the owned layer itself, the adjoint of its deposit's fold).
    phase.reset();
    {
      ScopedPhase th(timers, Phase::FluidHalo);
      cellHalo.gather(f.Tmean, &timers, Exchange::IntraPhysics);
    }
    phase.emplace(timers, Phase::FluidMomentum);
  }
  applyScalarBc(dec, f.T);
  tGhostsFresh = true;
  double v[7] = {stepBnd[0], stepBnd[1], stepBnd[2], stepBnd[3],
                 stepBnd[4], stepBnd[5], stepSource};
  dec.comm().sumInPlace(std::span<double>(v, 7));
  for (int b = 0; b < 6; ++b) heatFace[static_cast<std::size_t>(b)] += v[b];
  heatSourceTotal += v[6];
  heatSubstepsLast = N;
}

}  // namespace coloc::fv
