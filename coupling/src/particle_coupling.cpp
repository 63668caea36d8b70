#include "particle_coupling.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "coloc/core/error.hpp"

namespace coloc::coupling {

namespace {
constexpr double kPi = std::numbers::pi;
}

ParticleCoupling::ParticleCoupling(const Config& cfg, const Decomposition& dec, Timers& timers,
                                   bool frozen)
    : dec_(&dec),
      timers_(&timers),
      kernel_(kernelFromName(cfg.string("coupling.kernel"))),
      drag_(dragLawFromName(cfg.string("coupling.drag"))),
      selfVelocity_(selfVelocityFromConfig(cfg)),
      frozen_(frozen),
      epsMin_(cfg.number("coupling.eps_min")),
      rhoF_(cfg.number("fluid.rho")),
      nu_(cfg.number("fluid.nu")),
      heatLaw_(heatLawFromConfig(cfg)) {
  if (!convects()) return;
  // (the case checks made fluid.heat and particles.heat required with convection, and with them
  // these optional keys)
  kF_ = cfg.optionalNumber("fluid.conductivity").value_or(0.0);
  if (!(kF_ > 0))
    throw ConfigError("fluid.conductivity",
                      "convection (coupling.heat_transfer) needs a fluid conductivity > 0");
  prandtl3_ =
      std::cbrt(rhoF_ * nu_ * cfg.optionalNumber("fluid.heat_capacity").value_or(0.0) / kF_);
  for (const auto& m : cfg.at("particles.materials")) {
    cpOfMaterial_.push_back(m.value("heat_capacity", 0.0));
    kOfMaterial_.push_back(m.value("conductivity", 0.0));
  }
}

void ParticleCoupling::resize(std::size_t n) {
  if (volume_.size() >= n) return;
  const std::size_t cap = std::max(n, volume_.size() + volume_.size() / 4);
  for (auto* v : {&volume_, &beta_, &epsAt_}) v->resize(cap);
  for (int d = 0; d < 3; ++d)
    for (auto* a : {&uAt_, &vDep_, &gradPAt_, &ownPressure_}) (*a)[d].resize(cap);
  if (convects())
    for (auto* v : {&TAt_, &hEff_}) v->resize(cap);
}

void ParticleCoupling::locate(const ParticleView& view, const FieldLayout& layout) {
  view_ = view;
  const std::size_t n = view_.n;
  resize(n);
  const long long bad = stencils_.compute(
      kernel_, *dec_, layout, std::span<const double>(view_.x[0], n),
      std::span<const double>(view_.x[1], n), std::span<const double>(view_.x[2], n), n);
  std::string err;
  if (bad >= 0) {
    const auto i = static_cast<std::size_t>(bad);
    err = fmt::format(
        "particle {} at ({:g}, {:g}, {:g}) is more than one cell outside its block: it cannot be "
        "coupled (check particles.skin and the time step)",
        view_.id[i], view_.x[0][i], view_.x[1][i], view_.x[2][i]);
  }
  dec_->comm().raiseIfAny(err);
  // The volumes: one pow per distinct radius in a run of equal radii (the same values).
  double r = std::numeric_limits<double>::quiet_NaN(), vol = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (view_.radius[i] != r) r = view_.radius[i], vol = 4.0 / 3.0 * kPi * std::pow(r, 3);
    volume_[i] = vol;
  }
}

void ParticleCoupling::evaluateDrag(const DragFields* fields, double dt, double time) {
  const std::size_t n = stencils_.count();
  const bool self = selfVelocity_ != SelfVelocity::None;
  failure_.clear();
  biotMax_ = 0;
  // Range by range (kSampleChunk particles): the fields sampled at them, then the drag, which
  // reads the sampled values while they are still in cache. Each phase is timed as its own.
  for (std::size_t s0 = 0; s0 < n; s0 += kSampleChunk) {
    const std::size_t sn = std::min(kSampleChunk, n - s0);
    if (fields) {
      // The 7 fields at these particles in one pass over their stencils (kernel.hpp), just
      // before the drag reads them (still in cache).
      ScopedPhase ts(*timers_, Phase::CouplingInterpolate);
      double* out[7] = {epsAt_.data() + s0};
      for (int d = 0; d < 3; ++d) {
        out[1 + d] = uAt_[d].data() + s0;
        out[4 + d] = gradPAt_[d].data() + s0;
      }
      interpolate(stencils_, *fields, out, s0, sn);
    }
    evaluateDragOn(s0, sn, dt, time);
    if (convects()) exchangeHeatOn(s0, sn, dt, fields != nullptr);
  }
  if (self) dec_->comm().raiseIfAny(failure_);
}

void ParticleCoupling::evaluateDragOn(std::size_t first, std::size_t count, double dt,
                                      double time) {
  const ParticleView& p = view_;
  const bool self = selfVelocity_ != SelfVelocity::None;
  const double vCell = dec_->grid().cellVolume();
  const bool still = frozen_ || dt <= 0;
  auto& [cEps, cD, cSlip, cBeta] = dragChunk_;
  for (std::size_t i0 = first; i0 < first + count; i0 += kDragChunk) {
    const std::size_t m = std::min(kDragChunk, first + count - i0);
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t i = i0 + j;
      const double s0 = uAt_[0][i] - p.v[0][i], s1 = uAt_[1][i] - p.v[1][i],
                   s2 = uAt_[2][i] - p.v[2][i];
      cSlip[j] = std::sqrt(s0 * s0 + s1 * s1 + s2 * s2);
      cEps[j] = std::clamp(epsAt_[i], epsMin_, 1.0);
      cD[j] = 2.0 * p.radius[i];
    }
    if (self) {
      // With the correction the drag law sees the undisturbed fluid fraction too: the sampled
      // one less the particle's own volume, deposited and read back with the same weights (its
      // share V / h^3 sum_c w_c^2; self_velocity.hpp).
      for (std::size_t j = 0; j < m; ++j) {
        const std::size_t i = i0 + j;
        double w2 = volume_[i] / vCell;
        for (int d = 0; d < 3; ++d) {
          const double f = stencils_.fraction(d, i);
          w2 *= (1.0 - f) * (1.0 - f) + f * f;
        }
        cEps[j] = std::clamp(epsAt_[i] + w2, epsMin_, 1.0);
      }
    }
    dragCoefficients(drag_, {cEps.data(), m}, {cD.data(), m}, {cSlip.data(), m}, rhoF_, nu_,
                     {cBeta.data(), m});
    // Each particle's implicit response.
    if (self || still) {
      for (std::size_t j = 0; j < m; ++j)
        respondToDrag(i0 + j, cEps[j], cSlip[j], cBeta[j], dt, time, still, self);
      continue;
    }
    // The common case, respondToDrag's arithmetic without the correction, array by array (the
    // same two functions, inlined: the loops vectorise).
    for (std::size_t j = 0; j < m; ++j)
      beta_[i0 + j] = cBeta[j] / responseDenominator(cBeta[j], dt, p.mass[i0 + j]);
    // (no held force: force - 0.0, as ParticleView::nonDrag)
    static constexpr std::array<double, kDragChunk> kNoneHeld{};
    for (int d = 0; d < 3; ++d) {
      const double *v = p.v[d] + i0, *force = p.force[d] + i0, *mass = p.mass + i0,
                   *vol = volume_.data() + i0, *gradP = gradPAt_[d].data() + i0,
                   *held = p.held[d] ? p.held[d] + i0 : kNoneHeld.data();
      double* out = vDep_[d].data() + i0;
      for (std::size_t j = 0; j < m; ++j)
        out[j] = velocityWithoutDrag(v[j], force[j] - held[j], vol[j], gradP[j], dt, mass[j]);
    }
  }
}

void ParticleCoupling::exchangeHeatOn(std::size_t first, std::size_t count, double dt,
                                      bool sampled) {
  const ParticleView& p = view_;
  const std::size_t last = first + count;
  if (!sampled) {
    std::fill(hEff_.begin() + static_cast<std::ptrdiff_t>(first),
              hEff_.begin() + static_cast<std::ptrdiff_t>(last), 0.0);
    return;
  }
  double biot = biotMax_;
  for (std::size_t i = first; i < last; ++i) {
    const double s0 = uAt_[0][i] - p.v[0][i], s1 = uAt_[1][i] - p.v[1][i],
                 s2 = uAt_[2][i] - p.v[2][i];
    const double eps = std::clamp(epsAt_[i], epsMin_, 1.0), d = 2.0 * p.radius[i];
    const double re = eps * d * std::sqrt(s0 * s0 + s1 * s1 + s2 * s2) / nu_;
    const double nu = nusseltPr3(heatLaw_, eps, re, prandtl3_);
    const auto mat = static_cast<std::size_t>(p.material[i]);
    // H = h A = Nu k_f / d * pi d^2; the particle's backward-Euler response over dt.
    const double H = nu * kF_ * kPi * d;
    const double capacity = p.mass[i] * cpOfMaterial_[mat];
    hEff_[i] = dt > 0 ? H / (1.0 + dt * H / capacity) : H;
    biot = std::max(biot, nu * kF_ / (6.0 * kOfMaterial_[mat]));
  }
  biotMax_ = biot;
}

void ParticleCoupling::respondToDrag(std::size_t i, double eps, double slip, double beta, double dt,
                                     double time, bool still, bool self) {
  const ParticleView& p = view_;
  const double epsFluid = std::clamp(epsAt_[i], epsMin_, 1.0);
  // 1 + dt beta / m - c beta: the implicit particle response and the self-induced velocity
  // (self_velocity.hpp); c = 0 without the correction.
  double denom = still ? 1.0 : responseDenominator(beta, dt, p.mass[i]);
  std::array<double, 3> ownPressure{};
  if (self)
    denom = correctForSelfVelocity(i, epsFluid, eps, slip, still ? 0.0 : dt,
                                   time + std::max(dt, 0.0), beta, ownPressure);
  beta_[i] = beta / denom;
  if (still) {
    // Particles that cannot move: the plain coefficient and their (zero) velocity.
    for (int d = 0; d < 3; ++d) {
      vDep_[d][i] = p.v[d][i];
      ownPressure_[d][i] = 0.0;
    }
    return;
  }
  // Implicit particle response (simulation.hpp): beta' = beta / (1 + dt beta / m) and the
  // velocity the particle would reach without drag, v~ = v + dt a, with a the non-drag
  // acceleration: contacts and gravity (the DEM's last total force less the coupling force it
  // held) and the pressure-gradient force -V rho_f grad p^n.
  const double m = p.mass[i];
  for (int d = 0; d < 3; ++d) {
    vDep_[d][i] =
        velocityWithoutDrag(p.v[d][i], p.nonDrag(d, i), volume_[i], gradPAt_[d][i], dt, m);
    if (self) {
      // The pressure-gradient force of the undisturbed fluid: less the particle's own share
      // V k F_d, F_d = beta_eff (u_at - v~) with v~ = v + dt (a - V k F_d / m) (implicit).
      const double k = volume_[i] * ownPressure[d];
      ownPressure_[d][i] = k;
      const double F = beta_[i] * (uAt_[d][i] - vDep_[d][i]) / (1.0 - beta_[i] * dt * k / m);
      vDep_[d][i] -= dt * k * F / m;
    }
  }
}

double ParticleCoupling::correctForSelfVelocity(std::size_t i, double epsFluid,
                                                double epsUndisturbed, double slipSampled,
                                                double dt, double tRun, double& beta,
                                                std::array<double, 3>& pressure) {
  // The drag law sees the undisturbed slip |u_at + c F - v| = slip / (1 - c beta'), beta' the
  // coefficient with the particle's implicit response; c depends on the coefficient the fluid
  // takes implicitly, beta_eff = beta / denom. A few fixed-point passes (c changes by a few
  // per cent with beta_eff; beta depends on the slip only through Re).
  const ParticleView& p = view_;
  const double h = dec_->grid().spacing(0), mu = rhoF_ * nu_, d = 2.0 * p.radius[i];
  std::array<double, 3> dir{0.0, 0.0, 1.0}, t{};
  if (slipSampled > 0)
    for (int a = 0; a < 3; ++a) dir[a] = (uAt_[a][i] - p.v[a][i]) / slipSampled;
  for (int a = 0; a < 3; ++a) t[a] = stencils_.fraction(a, i);
  const double inertia = dt > 0 ? dt / p.mass[i] : 0.0;
  double denom = 1.0 + inertia * beta;
  for (int pass = 0; pass < 4; ++pass) {
    const SelfResponse r = selfMobility(t, dir, h, mu, nu_, epsFluid, tRun, beta / denom);
    const double c = r.mobility;
    const double cb = c * beta / (1.0 + inertia * beta);  // c beta'
    if (!(cb < 0.5)) {
      if (failure_.empty()) {
        failure_ = fmt::format(
            "coupling.self_velocity: particle {} (d/h = {:g}) is too large for the correction "
            "(its self-induced velocity would be {:g} of its slip; the model holds below 0.5): "
            "use larger cells or coupling.self_velocity = none",
            p.id[i], d / h, cb);
      }
      return denom;
    }
    if (drag_ != DragLaw::Stokes) {
      // The same (batched) law as evaluateDrag, on one particle.
      const double slip = slipSampled / (1.0 - cb);
      dragCoefficients(drag_, {&epsUndisturbed, 1}, {&d, 1}, {&slip, 1}, rhoF_, nu_, {&beta, 1});
    }
    denom = 1.0 + inertia * beta - c * beta;
    pressure = r.pressure;
  }
  return denom;
}

void ParticleCoupling::deposit(CellField& solid, CellField& K, const std::array<CellField*, 3>& KUp,
                               CellField* heatSource, CellField* heatCoefficient) const {
  const double vCell = dec_->grid().cellVolume();
  const double s = 1.0 / (rhoF_ * vCell);
  // The 5 deposits (7 with convection) in one pass over the stencils (kernel.hpp); beta v~ is
  // formed, not stored.
  const DepositTerm terms[7] = {{volume_.data(), nullptr, 1.0 / vCell, &solid},
                                {beta_.data(), nullptr, s, &K},
                                {beta_.data(), vDep_[0].data(), s, KUp[0]},
                                {beta_.data(), vDep_[1].data(), s, KUp[1]},
                                {beta_.data(), vDep_[2].data(), s, KUp[2]},
                                {hEff_.data(), view_.temperature, 1.0, heatSource},
                                {hEff_.data(), nullptr, 1.0, heatCoefficient}};
  const bool heat = convects() && heatSource && heatCoefficient;
  coupling::deposit(stencils_, std::span<const DepositTerm>(terms, heat ? 7 : 5));
}

void ParticleCoupling::sampleForForces(const ForceFields& fields) {
  double* out[7];
  for (int d = 0; d < 3; ++d) {
    out[d] = uAt_[d].data();
    out[3 + d] = gradPAt_[d].data();
  }
  out[6] = convects() ? TAt_.data() : nullptr;
  const std::size_t n = convects() ? 7 : 6;
  interpolate(stencils_, std::span<const CellField* const>(fields.data(), n),
              std::span<double* const>(out, n));
}

void ParticleCoupling::applyForces(const std::array<double*, 3>& out, double dt,
                                   double sums[9]) const {
  const std::size_t n = stencils_.count();
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      const double drag = beta_[i] * (uAt_[d][i] - vDep_[d][i]);
      out[d][i] = drag - volume_[i] * rhoF_ * gradPAt_[d][i];
      // With the correction, the pressure-gradient force of the undisturbed fluid: less the
      // particle's own share (evaluateDrag; particles that cannot move have none).
      if (selfVelocity_ != SelfVelocity::None) out[d][i] -= ownPressure_[d][i] * drag;
      sums[d] += drag * dt;
      sums[6 + d] += beta_[i] * (std::abs(uAt_[d][i]) + std::abs(vDep_[d][i])) * dt;
    }
  }
}

void ParticleCoupling::applyHeat(double* out, double dt, double sums[3]) const {
  const std::size_t n = stencils_.count();
  const double* Tp = view_.temperature;
  for (std::size_t i = 0; i < n; ++i) {
    const double q = hEff_[i] * (TAt_[i] - Tp[i]);
    out[i] = q;
    sums[0] += q * dt;
    sums[1] += hEff_[i] * (std::abs(TAt_[i]) + std::abs(Tp[i])) * dt;
    sums[2] += std::abs(q) * dt;
  }
}

}  // namespace coloc::coupling
