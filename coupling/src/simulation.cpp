#include "coloc/coupling/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "coloc/core/error.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

void declareConfig(Schema& s) {
  s.string("coupling.kernel", "trilinear",
           "deposition/interpolation kernel: centroid (PCM) or trilinear (cloud-in-cell)",
           {"centroid", "trilinear"});
  s.string("coupling.drag", "difelice", "drag law: stokes, difelice, gidaspow, beetstra",
           {"stokes", "difelice", "gidaspow", "beetstra"});
  s.number("coupling.eps_min", 0.3, "lower clip of the fluid fraction", Range::openClosed(0.0, 1.0));
  s.integer("coupling.dem_substeps", 0,
            "DEM sub-steps per CFD step; 0: the CFD step divided by particles.dt",
            Range::nonNegative());
}

Schema caseSchema() {
  Schema s;
  declareRunConfig(s);
  declareDomainConfig(s);
  fv::declareConfig(s);
  dem::declareConfig(s);
  declareConfig(s);
  declareOutputConfig(s);
  return s;
}

namespace {
constexpr double kPi = std::numbers::pi;
}

Simulation::Simulation(const Comm& world, const Config& cfg)
    : cfg_(cfg), dec_(decompositionFromConfig(world, cfg)), mode_(runMode(cfg)) {
  ScopedPhase setup(timers_, Phase::Setup);
  maxSteps_ = cfg.integer("run.steps");
  steadyTol_ = cfg.number("fluid.steady_tol");
  endTime_ = cfg.number("run.end_time");
  if (maxSteps_ == 0 && endTime_ <= 0)
    throw ConfigError("run.steps", "give run.steps > 0 or run.end_time > 0");
  if (mode_ != RunMode::ParticlesOnly) fluid_ = std::make_unique<fv::FluidSolver>(dec_, cfg, timers_);
  if (mode_ != RunMode::FluidOnly) {
    dem_ = std::make_unique<dem::DemSolver>(dec_, cfg, timers_);
    if (mode_ == RunMode::DummyDem) dem_->setFrozen(true);
  }
  coupled_ = mode_ == RunMode::Coupled || mode_ == RunMode::DummyDem;
  if (!coupled_) return;

  kernel_ = kernelFromName(cfg.string("coupling.kernel"));
  drag_ = dragLawFromName(cfg.string("coupling.drag"));
  epsMin_ = cfg.number("coupling.eps_min");
  rhoF_ = cfg.number("fluid.rho");
  nu_ = cfg.number("fluid.nu");
  const FieldLayout layout = fluid_->fields().p.layout();
  solid_ = CellField(layout);
  eps_ = CellField(layout, 1.0);
  for (int d = 0; d < 3; ++d) {
    uCell_[d] = CellField(layout);
    uCellOld_[d] = CellField(layout);
    gradP_[d] = CellField(layout);
  }
  halo_ = HaloPlan(dec_, layout);

  // The initial porosity: deposit the particle volume once and start with eps^0 = eps^1 so the
  // first step sees no spurious d(eps)/dt.
  computeStencils();
  evaluateDrag(0.0);  // beta is not used yet (K starts at zero)
  depositParticles();
  sumDepositsAcrossBlocks();
  updateFluidCoefficients();
  auto& f = fluid_->fields();
  f.K.fill(0.0);
  for (auto& k : f.KUp) k.fill(0.0);
  fluid_->syncEpsOld();
  refreshCellVelocity();
  fluid_->pressureGradient(gradP_);
  for (auto& g : gradP_) fillWallGhostsByMirror(dec_, g);
}

Simulation::~Simulation() = default;

bool Simulation::finished() const {
  // A fluid-only run may stop at steady state (same verdict on every rank).
  if (mode_ == RunMode::FluidOnly && steadyTol_ > 0 && steps_ > 1 &&
      fluid_->steadyResidual() < steadyTol_)
    return true;
  if (maxSteps_ > 0) return steps_ >= maxSteps_;
  return time_ >= endTime_ * (1.0 - 1e-12);
}

void Simulation::step() {
  switch (mode_) {
    case RunMode::FluidOnly: {
      const double dt = fluid_->nextDt();
      advanceFluid(dt);
      lastDt_ = dt;
      break;
    }
    case RunMode::ParticlesOnly: {
      const long long n = std::max<long long>(1, cfg_.integer("coupling.dem_substeps"));
      advanceParticles(static_cast<int>(n));
      lastDt_ = static_cast<double>(n) * dem_->dt();
      break;
    }
    case RunMode::Coupled:
    case RunMode::DummyDem: {
      // The CFD step is a whole number of DEM steps, as large as the fluid allows.
      long long nSub = cfg_.integer("coupling.dem_substeps");
      if (nSub == 0)
        nSub = std::max<long long>(1, static_cast<long long>(std::floor(fluid_->nextDt() / dem_->dt() + 1e-9)));
      const double dt = static_cast<double>(nSub) * dem_->dt();
      computeStencils();
      sampleFluidForDrag();
      evaluateDrag(dt);
      depositParticles();
      sumDepositsAcrossBlocks();
      updateFluidCoefficients();
      advanceFluid(dt);
      refreshCellVelocity();
      sampleFluidForForces();
      applyCouplingForces(dt);
      handForcesToParticles();
      advanceParticles(static_cast<int>(nSub));
      lastDt_ = dt;
      break;
    }
  }
  time_ += lastDt_;
  ++steps_;
}

void Simulation::resizeParticleBuffers(std::size_t n) {
  if (volume_.size() >= n) return;
  const std::size_t cap = std::max(n, volume_.size() + volume_.size() / 4);
  for (auto* v : {&volume_, &beta_, &epsAt_}) v->resize(cap);
  for (int d = 0; d < 3; ++d)
    for (auto* a : {&uAt_, &vDep_, &betaV_, &gradPAt_, &force_}) (*a)[d].resize(cap);
}

void Simulation::computeStencils() {
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  const auto& p = dem_->particles();
  const std::size_t n = p.nOwned;
  resizeParticleBuffers(n);
  const long long bad = stencils_.compute(kernel_, dec_, solid_.layout(), p.x[0], p.x[1], p.x[2], n);
  std::string err;
  if (bad >= 0) {
    const auto i = static_cast<std::size_t>(bad);
    std::ostringstream os;
    os << "particle " << p.id[i] << " at (" << p.x[0][i] << ", " << p.x[1][i] << ", " << p.x[2][i]
       << ") is more than one cell outside its block: it cannot be coupled (check particles.skin "
          "and the time step)";
    err = os.str();
  }
  dec_.comm().raiseIfAny(err);
  for (std::size_t i = 0; i < n; ++i) volume_[i] = 4.0 / 3.0 * kPi * std::pow(p.radius[i], 3);
}

void Simulation::sampleFluidForDrag() {
  ScopedPhase t(timers_, Phase::CouplingInterpolate);
  interpolate(stencils_, eps_, epsAt_);
  for (int d = 0; d < 3; ++d) {
    interpolate(stencils_, uCell_[d], uAt_[d]);
    interpolate(stencils_, gradP_[d], gradPAt_[d]);
  }
}

void Simulation::evaluateDrag(double dt) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  const auto& p = dem_->particles();
  const std::size_t n = stencils_.count();
  const bool frozen = mode_ == RunMode::DummyDem;
  for (std::size_t i = 0; i < n; ++i) {
    double slip2 = 0;
    for (int d = 0; d < 3; ++d) {
      const double s = uAt_[d][i] - p.v[d][i];
      slip2 += s * s;
    }
    const double eps = std::clamp(epsAt_[i], epsMin_, 1.0);
    const double beta = dragCoefficient(drag_, eps, 2.0 * p.radius[i], std::sqrt(slip2), rhoF_, nu_);
    if (frozen || dt <= 0) {
      // Particles that cannot move: the plain coefficient and their (zero) velocity.
      beta_[i] = beta;
      for (int d = 0; d < 3; ++d) vDep_[d][i] = p.v[d][i];
    } else {
      // Implicit particle response (see the header): beta' = beta / (1 + dt beta / m) and the
      // velocity the particle would reach without drag, v~ = v + dt a, with a the non-drag
      // acceleration: contacts and gravity (the DEM's last total force less the coupling force
      // it held) and the pressure-gradient force -V rho_f grad p^n.
      const double m = p.mass[i];
      beta_[i] = beta / (1.0 + dt * beta / m);
      for (int d = 0; d < 3; ++d) {
        const double nonDrag = p.f[d][i] - p.fExt[d][i] - volume_[i] * rhoF_ * gradPAt_[d][i];
        vDep_[d][i] = p.v[d][i] + dt * nonDrag / m;
      }
    }
    for (int d = 0; d < 3; ++d) betaV_[d][i] = beta_[i] * vDep_[d][i];
  }
}

void Simulation::depositParticles() {
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  auto& f = fluid_->fields();
  const double vCell = dec_.grid().cellVolume();
  const double s = 1.0 / (rhoF_ * vCell);
  solid_.fill(0.0);
  f.K.fill(0.0);
  for (int d = 0; d < 3; ++d) f.KUp[d].fill(0.0);
  const std::size_t n = stencils_.count();
  deposit(stencils_, std::span<const double>(volume_.data(), n), 1.0 / vCell, solid_);
  deposit(stencils_, std::span<const double>(beta_.data(), n), s, f.K);
  for (int d = 0; d < 3; ++d)
    deposit(stencils_, std::span<const double>(betaV_[d].data(), n), s, f.KUp[d]);
}

void Simulation::sumDepositsAcrossBlocks() {
  ScopedPhase t(timers_, Phase::ExchangeRemote);
  auto& f = fluid_->fields();
  Field3<double>* fields[5] = {&solid_, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2]};
  halo_.scatterSum(fields, Fold::Mirror, &timers_, Exchange::InterPhysicsRemote);
}

void Simulation::updateFluidCoefficients() {
  {
    ScopedPhase t(timers_, Phase::CouplingDeposit);
    auto& f = fluid_->fields();
    double solid = 0;
    forEach(solid_.interior(), [&](int i, int j, int k) {
      solid += solid_(i, j, k);
      const double e = std::clamp(1.0 - solid_(i, j, k), epsMin_, 1.0);
      f.eps(i, j, k) = e;
      eps_(i, j, k) = e;
    });
    solidVolume_ = dec_.comm().sum(solid) * dec_.grid().cellVolume();
  }
  ScopedPhase t(timers_, Phase::FluidHalo);
  halo_.gather(eps_, &timers_, Exchange::IntraPhysics);
  fillWallGhostsByMirror(dec_, eps_);
  fluid_->markCoefficientsChanged();
}

void Simulation::advanceFluid(double dt) {
  fluid_->step(dt);
  lastStepDt_ = dt;
}

void Simulation::refreshCellVelocity() {
  ScopedPhase t(timers_, Phase::FluidCellFields);
  std::swap(uCell_, uCellOld_);
  fluid_->cellVelocity(uCell_);
  for (auto& u : uCell_) fillWallGhostsByMirror(dec_, u);
  // L1 norm of the fluid acceleration over the step (time series of benchmark 1).
  if (lastStepDt_ > 0) {
    double accel = 0;
    forEach(solid_.interior(), [&](int i, int j, int k) {
      for (int d = 0; d < 3; ++d) accel += std::abs(uCell_[d](i, j, k) - uCellOld_[d](i, j, k));
    });
    accelL1_ = dec_.comm().sum(accel) * dec_.grid().cellVolume() / lastStepDt_;
  }
}

void Simulation::sampleFluidForForces() {
  {
    ScopedPhase t(timers_, Phase::FluidCellFields);
    fluid_->pressureGradient(gradP_);
    for (auto& g : gradP_) fillWallGhostsByMirror(dec_, g);
  }
  ScopedPhase t(timers_, Phase::CouplingInterpolate);
  for (int d = 0; d < 3; ++d) {
    interpolate(stencils_, uCell_[d], uAt_[d]);
    interpolate(stencils_, gradP_[d], gradPAt_[d]);
  }
}

void Simulation::applyCouplingForces(double dt) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  const std::size_t n = stencils_.count();
  // sums: particle drag impulse (3), fluid drag momentum change (3), gross magnitude of the
  // exchanged terms sum beta' (|u| + |v~|) dt (3): the scale of round-off in the balance.
  double sums[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      const double drag = beta_[i] * (uAt_[d][i] - vDep_[d][i]);
      force_[d][i] = drag - volume_[i] * rhoF_ * gradPAt_[d][i];
      sums[d] += drag * dt;
      sums[6 + d] += beta_[i] * (std::abs(uAt_[d][i]) + std::abs(vDep_[d][i])) * dt;
    }
  }
  // What the fluid lost through its drag term over the step: rho V (K u - K u_p) dt per cell.
  const auto& f = fluid_->fields();
  const double rv = rhoF_ * dec_.grid().cellVolume() * dt;
  forEach(solid_.interior(), [&](int i, int j, int k) {
    for (int d = 0; d < 3; ++d)
      sums[3 + d] -= rv * (f.K(i, j, k) * uCell_[d](i, j, k) - f.KUp[d](i, j, k));
  });
  dec_.comm().sumInPlace(std::span<double>(sums, 9));
  double gross = 0, diff = 0;
  for (int d = 0; d < 3; ++d) {
    particleImpulse_[d] = sums[d];
    fluidImpulse_[d] = sums[3 + d];
    gross = std::max(gross, sums[6 + d]);
    diff = std::max(diff, std::abs(sums[d] + sums[3 + d]));
  }
  if (gross > 0) momentumResidual_ = std::max(momentumResidual_, diff / gross);
}

void Simulation::handForcesToParticles() {
  ScopedPhase t(timers_, Phase::ExchangeLocal);
  auto& p = dem_->particles();
  const std::size_t n = stencils_.count();
  for (int d = 0; d < 3; ++d) std::copy_n(force_[d].data(), n, p.fExt[d].data());
  timers_.book(Exchange::InterPhysicsLocal, static_cast<long long>(3 * n * sizeof(double)), 0);
}

void Simulation::advanceParticles(int n) {
  for (int s = 0; s < n; ++s) dem_->substep();
  substeps_ += n;
}

void Simulation::writeOutput(OutputWriter& out) {
  if (!out.due(steps_)) return;
  ScopedPhase t(timers_, Phase::Output);
  if (fluid_ && out.options().fields) {
    const auto& f = fluid_->fields();
    if (!coupled_) {
      // Fluid-only runs keep no cell-centred velocity; make it for the output.
      if (uCell_[0].layout() != f.p.layout())
        for (auto& u : uCell_) u = CellField(f.p.layout());
      fluid_->cellVelocity(uCell_);
    }
    out.writeFields(steps_, time_,
                    {OutputField::scalar("p", f.p), OutputField::vector("u", uCell_),
                     OutputField::scalar("eps", f.eps), OutputField::scalar("K", f.K)});
  }
  if (dem_ && out.options().particles) {
    const auto& p = dem_->particles();
    const std::size_t n = p.nOwned;
    out.writeParticles(steps_, time_, std::span<const std::int64_t>(p.id.data(), n),
                       firstRows(p.x, n), firstRows(p.v, n), firstRows(p.omega, n),
                       std::span<const double>(p.radius.data(), n));
  }
}

Json Simulation::report(double wallSeconds) const {
  const Comm& comm = dec_.comm();
  Json out = timers_.report(comm, wallSeconds);
  const double wall = comm.max(wallSeconds);
  out["mpi"] = {{"ranks", comm.size()}, {"dims", {dec_.dims()[0], dec_.dims()[1], dec_.dims()[2]}}};
  out["run"] = {{"mode", runModeName(mode_)},
                {"steps", steps_},
                {"dem_substeps", substeps_},
                {"sim_time", time_},
                {"wall_s", wall}};
  const long long particles = dem_ ? dem_->globalCount() : 0;
  const double cells = static_cast<double>(dec_.grid().cellCount());
  out["throughput"] = {
      {"cell_steps_per_s", fluid_ && wall > 0 ? cells * static_cast<double>(steps_) / wall : 0.0},
      {"particle_steps_per_s",
       dem_ && wall > 0 ? static_cast<double>(particles) * static_cast<double>(substeps_) / wall : 0.0}};
  out["checks"] = {{"momentum_balance", momentumResidual_}, {"mass_balance", 0.0}};
  if (fluid_) {
    const Json fd = fluid_->diagnostics();
    for (auto& [k, v] : fd.items()) {
      if (out.contains(k) && out[k].is_object() && v.is_object())
        for (auto& [k2, v2] : v.items()) out[k][k2] = v2;
      else
        out[k] = v;
    }
  }
  if (dem_) {
    const Json pd = dem_->diagnostics();
    for (auto& [k, v] : pd.items()) {
      if (out.contains(k) && out[k].is_object() && v.is_object())
        for (auto& [k2, v2] : v.items()) out[k][k2] = v2;
      else
        out[k] = v;
    }
  }
  if (coupled_) out["coupling"] = {{"solid_volume", solidVolume_},
                                   {"kernel", kernel_ == KernelKind::Centroid ? "centroid" : "trilinear"},
                                   {"drag", dragLawName(drag_)}};
  return out;
}

}  // namespace coloc::coupling
