#include "coloc/coupling/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <utility>

#include "coloc/core/error.hpp"
#include "coloc/core/fault.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/coupling/self_velocity.hpp"
#include "coloc/partition/remap.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

namespace {
constexpr double kPi = std::numbers::pi;
}

Simulation::Simulation(const Comm& world, const Config& cfg)
    : Simulation(cfg, chooseLayouts(world, cfg)) {}

Simulation::Simulation(const Config& cfg, Layouts layouts)
    : Simulation(cfg, std::move(layouts), nullptr, nullptr) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, const std::string& checkpoint)
    : Simulation(cfg, std::move(layouts), &checkpoint, nullptr) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, Simulation& from)
    : Simulation(cfg, std::move(layouts), nullptr, &from) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, const std::string* checkpoint,
                       Simulation* from)
    : cfg_(cfg),
      layouts_(std::move(layouts)),
      dec_(layouts_.fluid),
      demDec_(layouts_.particles),
      mode_(runMode(cfg)) {
  ScopedPhase setup(timers_, Phase::Setup);
  maxSteps_ = cfg.integer("run.steps");
  steadyTol_ = cfg.number("fluid.steady_tol");
  endTime_ = cfg.number("run.end_time");
  demSubsteps_ = cfg.integer("coupling.dem_substeps");
  timers_.setSyncPoints(cfg.boolean("run.timer_sync"));
  if (maxSteps_ == 0 && endTime_ <= 0)
    throw ConfigError("run.steps", "give run.steps > 0 or run.end_time > 0");
  // Restart: the checkpoint is checked (status, grid, mode) and read on these blocks.
  std::optional<H5File> file;
  if (checkpoint) {
    checkRestartable(dec_.comm(), *checkpoint, dec_.grid(), mode_);
    file.emplace(H5File::openRead(dec_.comm(), *checkpoint));
    fault::point("restart", 0);
  }
  if (mode_ != RunMode::ParticlesOnly) {
    fluid_ = std::make_unique<fv::FluidSolver>(dec_, cfg, timers_);
    if (file) readFluidState(*file, "/fluid", dec_, *fluid_);
    if (from) remapFluid(*from);
  }
  fault::point("setup", 0);
  if (mode_ != RunMode::FluidOnly) {
    if (file) {
      dem::DemState state = readDemState(*file, "/particles");
      validateDemState(dec_.comm(), state, dec_.grid(), cfg.at("particles.materials").size(),
                       *checkpoint);
      dem_ =
          std::make_unique<dem::DemSolver>(particleDecomposition(), cfg, timers_, std::move(state));
    } else if (from) {
      // The DEM's own restoring constructor sends every row to the owner of its position.
      dem_ = std::make_unique<dem::DemSolver>(particleDecomposition(), cfg, timers_,
                                              from->dem_->saveState());
    } else {
      dem_ = std::make_unique<dem::DemSolver>(particleDecomposition(), cfg, timers_);
    }
    if (mode_ == RunMode::DummyDem) dem_->setFrozen(true);
    transfer_ = demDec_ ? proxyTransfer(dec_, *dem_) : colocatedTransfer(*dem_);
  }
  if (file) {
    run_ = readRunCounters(*file, "/simulation");
    file->close();
  }
  if (from) run_ = from->run_;
  coupled_ = mode_ == RunMode::Coupled || mode_ == RunMode::DummyDem;
  if (!coupled_) return;

  kernel_ = kernelFromName(cfg.string("coupling.kernel"));
  drag_ = dragLawFromName(cfg.string("coupling.drag"));
  selfVelocity_ = selfVelocityFromConfig(cfg);
  epsMin_ = cfg.number("coupling.eps_min");
  smoothingPasses_ = static_cast<int>(cfg.integer("coupling.smoothing_passes"));
  rhoF_ = cfg.number("fluid.rho");
  nu_ = cfg.number("fluid.nu");
  const FieldLayout layout = std::as_const(*fluid_).fields().p.layout();
  solid_ = CellField(layout);
  scratch_ = CellField(layout);
  for (int d = 0; d < 3; ++d) {
    uCell_[d] = CellField(layout);
    uCellOld_[d] = CellField(layout);
    gradP_[d] = CellField(layout);
  }
  // Stencils reach one ghost layer: the coupling's halo plan moves (and folds) only that layer
  // of the fluid-layout fields, whatever ghost width the fluid keeps for itself.
  FieldLayout oneLayer = layout;
  oneLayer.ghost = 1;
  halo_ = HaloPlan(dec_, oneLayer, layout);

  if (checkpoint || from) {
    // What the last step left in the coupling's own fields: the cell-centred velocity and the
    // pressure gradient of u^{n+1}, p^{n+1} (eps and its ghosts: restored by the fluid).
    fluid_->cellVelocity(uCell_);
    for (auto& u : uCell_) fillWallGhostsByMirror(dec_, u);
    fluid_->pressureGradient(gradP_);
    for (auto& g : gradP_) fillWallGhostsByMirror(dec_, g);
    return;
  }
  // The initial porosity: deposit the particle volume once and start with eps^0 = eps^1 so the
  // first step sees no spurious d(eps)/dt.
  gatherParticles();
  computeStencils();
  evaluateDrag(0.0, nullptr);  // beta is not used yet (K starts at zero)
  depositParticles();
  sumDepositsAcrossBlocks();
  updateFluidCoefficients();
  auto f = fluid_->couplingInputs();
  f.K.fill(0.0);
  for (auto& k : f.KUp) k.fill(0.0);
  fluid_->startCoupling();
  refreshCellVelocity();
  fluid_->pressureGradient(gradP_);
  for (auto& g : gradP_) fillWallGhostsByMirror(dec_, g);
}

Simulation::~Simulation() = default;

void Simulation::remapFluid(const Simulation& from) {
  // The fluid's restart table, walked on both solvers in its one order: cell arrays in one
  // remap, the face arrays of each staggering in one remap each. The non-const walk marks the
  // new solver's ghosts and rates stale; restoreState sets them.
  std::vector<const Field3<double>*> src[4];  // [0..2]: faces normal to d; [3]: cell centred
  std::vector<Field3<double>*> dst[4];
  fv::forEachStateField(std::as_const(*from.fluid_),
                        [&](const fv::FluidSolver::StateField& sf, const Field3<double>* const* a) {
                          auto& v = src[sf.stagger >= 0 ? sf.stagger : 3];
                          v.insert(v.end(), a, a + sf.components);
                        });
  fv::forEachStateField(*fluid_,
                        [&](const fv::FluidSolver::StateField& sf, Field3<double>* const* a) {
                          auto& v = dst[sf.stagger >= 0 ? sf.stagger : 3];
                          v.insert(v.end(), a, a + sf.components);
                        });
  remapFields(from.dec_, src[3], dec_, dst[3]);
  for (int d = 0; d < 3; ++d) remapFields(from.dec_, src[d], dec_, dst[d], d);
  fluid_->restoreState(from.fluid_->counters());
}

void Simulation::beginRun() {
  timers_.beginRun();
  runStartSteps_ = run_.steps;
  runStartSubsteps_ = run_.substeps;
}

bool Simulation::finished() const {
  // A fluid-only run may stop at steady state (same verdict on every rank).
  if (mode_ == RunMode::FluidOnly && steadyTol_ > 0 && run_.steps > 1 &&
      fluid_->steadyResidual() < steadyTol_)
    return true;
  if (maxSteps_ > 0) return run_.steps >= maxSteps_;
  return run_.time >= endTime_ * (1.0 - 1e-12);
}

void Simulation::step() {
  switch (mode_) {
    case RunMode::FluidOnly: {
      const double dt = fluid_->nextDt();
      advanceFluid(dt);
      run_.lastDt = dt;
      break;
    }
    case RunMode::ParticlesOnly: {
      const long long n = std::max<long long>(1, demSubsteps_);
      advanceParticles(static_cast<int>(n));
      run_.lastDt = static_cast<double>(n) * dem_->dt();
      break;
    }
    case RunMode::Coupled:
    case RunMode::DummyDem: {
      // The CFD step is a whole number of DEM steps, as large as the fluid allows.
      long long nSub = demSubsteps_;
      if (nSub == 0)
        nSub = std::max<long long>(
            1, static_cast<long long>(std::floor(fluid_->nextDt() / dem_->dt() + 1e-9)));
      const double dt = static_cast<double>(nSub) * dem_->dt();
      waitForSlowestRank();
      gatherParticles();
      computeStencils();
      const DragFields fields = fluidForDrag();
      evaluateDrag(dt, &fields);
      fault::point("coupling", run_.steps + 1);
      depositParticles();
      waitForSlowestRank();
      sumDepositsAcrossBlocks();
      updateFluidCoefficients();
      advanceFluid(dt);
      refreshCellVelocity();
      sampleFluidForForces();
      applyCouplingForces(dt);
      handForcesToParticles();
      advanceParticles(static_cast<int>(nSub));
      run_.lastDt = dt;
      break;
    }
  }
  run_.time += run_.lastDt;
  ++run_.steps;
}

void Simulation::waitForSlowestRank() {
  // A timed barrier before the exchanges that follow the particle work (the DEM sub-steps, the
  // coupling arithmetic): the load imbalance is booked to `sync` (fractions.wait), so that the
  // exchange phases measure data movement, as the paper's inter-physics share does.
  if (dec_.size() == 1) return;
  ScopedPhase t(timers_, Phase::Sync);
  dec_.comm().barrier();
}

void Simulation::resizeParticleBuffers(std::size_t n) {
  if (volume_.size() >= n) return;
  const std::size_t cap = std::max(n, volume_.size() + volume_.size() / 4);
  for (auto* v : {&volume_, &beta_, &epsAt_}) v->resize(cap);
  for (int d = 0; d < 3; ++d)
    for (auto* a : {&uAt_, &vDep_, &gradPAt_, &ownPressure_}) (*a)[d].resize(cap);
}

void Simulation::gatherParticles() {
  view_ = transfer_->gather(timers_);
}

void Simulation::computeStencils() {
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  const std::size_t n = view_.n;
  resizeParticleBuffers(n);
  const long long bad = stencils_.compute(
      kernel_, dec_, solid_.layout(), std::span<const double>(view_.x[0], n),
      std::span<const double>(view_.x[1], n), std::span<const double>(view_.x[2], n), n);
  std::string err;
  if (bad >= 0) {
    const auto i = static_cast<std::size_t>(bad);
    std::ostringstream os;
    os << "particle " << view_.id[i] << " at (" << view_.x[0][i] << ", " << view_.x[1][i] << ", "
       << view_.x[2][i]
       << ") is more than one cell outside its block: it cannot be coupled (check particles.skin "
          "and the time step)";
    err = os.str();
  }
  dec_.comm().raiseIfAny(err);
  // The volumes: one pow per distinct radius in a run of equal radii (the same values).
  double r = std::numeric_limits<double>::quiet_NaN(), vol = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (view_.radius[i] != r) r = view_.radius[i], vol = 4.0 / 3.0 * kPi * std::pow(r, 3);
    volume_[i] = vol;
  }
}

const CellField& Simulation::sampled(const CellField& f, CellField& smoothed) {
  // With smoothing, the particles see S(f), S the filter applied to the deposits: the adjoint.
  if (smoothingPasses_ == 0) return f;
  if (!(smoothed.layout() == f.layout())) smoothed = CellField(f.layout());
  forEach(f.interior(), [&](int i, int j, int k) { smoothed(i, j, k) = f(i, j, k); });
  smoothField(smoothed);
  halo_.gather(smoothed);
  fillWallGhostsByMirror(dec_, smoothed);
  return smoothed;
}

Simulation::DragFields Simulation::fluidForDrag() {
  ScopedPhase t(timers_, Phase::CouplingInterpolate);
  // eps = 1 - S(solid) is smooth already; the fluid's eps^{n+1}, ghosts filled by its step.
  DragFields f{&std::as_const(*fluid_).fields().eps};
  for (int d = 0; d < 3; ++d) {
    f[1 + d] = &sampled(uCell_[d], uSmooth_[d]);
    f[4 + d] = &sampled(gradP_[d], gradPSmooth_[d]);
  }
  return f;
}

void Simulation::evaluateDrag(double dt, const DragFields* fields) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  const std::size_t n = stencils_.count();
  const bool self = selfVelocity_ != SelfVelocity::None;
  std::string err;
  // Range by range (kSampleChunk particles): the fields sampled at them, then the drag, which
  // reads the sampled values while they are still in cache. Each phase is timed as its own.
  for (std::size_t s0 = 0; s0 < n; s0 += kSampleChunk) {
    const std::size_t sn = std::min(kSampleChunk, n - s0);
    if (fields) {
      // The 7 fields at these particles in one pass over their stencils (kernel.hpp), just
      // before the drag reads them (still in cache).
      ScopedPhase ts(timers_, Phase::CouplingInterpolate);
      double* out[7] = {epsAt_.data() + s0};
      for (int d = 0; d < 3; ++d) {
        out[1 + d] = uAt_[d].data() + s0;
        out[4 + d] = gradPAt_[d].data() + s0;
      }
      interpolate(stencils_, *fields, out, s0, sn);
    }
    evaluateDragOn(s0, sn, dt, err);
  }
  if (self) dec_.comm().raiseIfAny(err);
}

void Simulation::evaluateDragOn(std::size_t first, std::size_t count, double dt, std::string& err) {
  const ParticleView& p = view_;
  const bool frozen = mode_ == RunMode::DummyDem;
  const bool self = selfVelocity_ != SelfVelocity::None;
  const double vCell = dec_.grid().cellVolume();
  const bool still = frozen || dt <= 0;
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
        respondToDrag(i0 + j, cEps[j], cSlip[j], cBeta[j], dt, still, self, err);
      continue;
    }
    // The common case, respondToDrag's arithmetic without the correction, array by array.
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t i = i0 + j;
      beta_[i] = cBeta[j] / (1.0 + dt * cBeta[j] / p.mass[i]);
    }
    // (no held force: force - 0.0, as ParticleView::nonDrag)
    static constexpr std::array<double, kDragChunk> kNoneHeld{};
    for (int d = 0; d < 3; ++d) {
      const double *v = p.v[d] + i0, *force = p.force[d] + i0, *mass = p.mass + i0,
                   *vol = volume_.data() + i0, *gradP = gradPAt_[d].data() + i0,
                   *held = p.held[d] ? p.held[d] + i0 : kNoneHeld.data();
      double* out = vDep_[d].data() + i0;
      for (std::size_t j = 0; j < m; ++j)
        out[j] = v[j] + dt * ((force[j] - held[j]) - vol[j] * rhoF_ * gradP[j]) / mass[j];
    }
  }
}

void Simulation::respondToDrag(std::size_t i, double eps, double slip, double beta, double dt,
                               bool still, bool self, std::string& err) {
  const ParticleView& p = view_;
  const double epsFluid = std::clamp(epsAt_[i], epsMin_, 1.0);
  // 1 + dt beta / m - c beta: the implicit particle response and the self-induced velocity
  // (self_velocity.hpp); c = 0 without the correction.
  double denom = still ? 1.0 : 1.0 + dt * beta / p.mass[i];
  std::array<double, 3> ownPressure{};
  if (self)
    denom = correctForSelfVelocity(i, epsFluid, eps, slip, still ? 0.0 : dt,
                                   run_.time + std::max(dt, 0.0), beta, ownPressure, err);
  if (still) {
    // Particles that cannot move: the plain coefficient and their (zero) velocity.
    beta_[i] = beta / denom;
    for (int d = 0; d < 3; ++d) {
      vDep_[d][i] = p.v[d][i];
      ownPressure_[d][i] = 0.0;
    }
  } else {
    // Implicit particle response (see the header): beta' = beta / (1 + dt beta / m) and the
    // velocity the particle would reach without drag, v~ = v + dt a, with a the non-drag
    // acceleration: contacts and gravity (the DEM's last total force less the coupling force
    // it held) and the pressure-gradient force -V rho_f grad p^n.
    const double m = p.mass[i];
    beta_[i] = beta / denom;
    for (int d = 0; d < 3; ++d) {
      const double nonDrag = p.nonDrag(d, i) - volume_[i] * rhoF_ * gradPAt_[d][i];
      vDep_[d][i] = p.v[d][i] + dt * nonDrag / m;
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
}

double Simulation::correctForSelfVelocity(std::size_t i, double epsFluid, double epsUndisturbed,
                                          double slipSampled, double dt, double tRun, double& beta,
                                          std::array<double, 3>& pressure, std::string& err) const {
  // The drag law sees the undisturbed slip |u_at + c F - v| = slip / (1 - c beta'), beta' the
  // coefficient with the particle's implicit response; c depends on the coefficient the fluid
  // takes implicitly, beta_eff = beta / denom. A few fixed-point passes (c changes by a few
  // per cent with beta_eff; beta depends on the slip only through Re).
  const ParticleView& p = view_;
  const double h = dec_.grid().spacing(0), mu = rhoF_ * nu_, d = 2.0 * p.radius[i];
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
      if (err.empty()) {
        std::ostringstream os;
        os << "coupling.self_velocity: particle " << p.id[i] << " (d/h = " << d / h
           << ") is too large for the correction (its self-induced velocity would be " << cb
           << " of its slip; the model holds below 0.5): use larger cells or "
           << "coupling.self_velocity = none";
        err = os.str();
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

void Simulation::depositParticles() {
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  auto f = fluid_->couplingInputs();
  const double vCell = dec_.grid().cellVolume();
  const double s = 1.0 / (rhoF_ * vCell);
  solid_.fill(0.0);
  f.K.fill(0.0);
  for (int d = 0; d < 3; ++d) f.KUp[d].fill(0.0);
  // The 5 deposits in one pass over the stencils (kernel.hpp); beta v~ is formed, not stored.
  const DepositTerm terms[5] = {{volume_.data(), nullptr, 1.0 / vCell, &solid_},
                                {beta_.data(), nullptr, s, &f.K},
                                {beta_.data(), vDep_[0].data(), s, &f.KUp[0]},
                                {beta_.data(), vDep_[1].data(), s, &f.KUp[1]},
                                {beta_.data(), vDep_[2].data(), s, &f.KUp[2]}};
  deposit(stencils_, terms);
}

void Simulation::sumDepositsAcrossBlocks() {
  // Across ranks only when a neighbour block is another rank's. On one rank the sum over a
  // periodic wrap is arithmetic inside the block, like the fold at walls: booked to deposition
  // (so a 1-rank run shows no across-ranks share without bytes).
  ScopedPhase t(timers_, halo_.crossesRanks() ? Phase::ExchangeRemote : Phase::CouplingDeposit);
  auto f = fluid_->couplingInputs();
  Field3<double>* fields[5] = {&solid_, &f.K, &f.KUp[0], &f.KUp[1], &f.KUp[2]};
  halo_.scatterSum(fields, Fold::Mirror, &timers_, Exchange::InterPhysicsRemote);
  if (smoothingPasses_ > 0) {
    ScopedPhase s(timers_, Phase::CouplingDeposit);
    for (auto* fld : fields) smoothField(*fld);
  }
}

void Simulation::smoothField(CellField& f) {
  for (int pass = 0; pass < smoothingPasses_; ++pass) smooth(dec_, halo_, f, scratch_);
}

void Simulation::updateFluidCoefficients() {
  // eps^{n+1} into the fluid's one eps array (owned cells); its step fills the ghosts.
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  auto f = fluid_->couplingInputs();
  double solid = 0;
  forEach(solid_.interior(), [&](int i, int j, int k) {
    solid += solid_(i, j, k);
    f.eps(i, j, k) = std::clamp(1.0 - solid_(i, j, k), epsMin_, 1.0);
  });
  run_.solidVolume = dec_.comm().sum(solid) * dec_.grid().cellVolume();
}

void Simulation::advanceFluid(double dt) {
  fault::point("fluid", run_.steps + 1);
  fluid_->step(dt);
  run_.lastStepDt = dt;
}

void Simulation::refreshCellVelocity() {
  ScopedPhase t(timers_, Phase::FluidCellFields);
  std::swap(uCell_, uCellOld_);
  fluid_->cellVelocity(uCell_);
  for (auto& u : uCell_) fillWallGhostsByMirror(dec_, u);
  // L1 norm of the fluid acceleration over the step (time series of benchmark 1).
  if (run_.lastStepDt > 0) {
    double accel = 0;
    forEach(solid_.interior(), [&](int i, int j, int k) {
      for (int d = 0; d < 3; ++d) accel += std::abs(uCell_[d](i, j, k) - uCellOld_[d](i, j, k));
    });
    run_.accelL1 = dec_.comm().sum(accel) * dec_.grid().cellVolume() / run_.lastStepDt;
  }
}

void Simulation::sampleFluidForForces() {
  {
    ScopedPhase t(timers_, Phase::FluidCellFields);
    fluid_->pressureGradient(gradP_);
    for (auto& g : gradP_) fillWallGhostsByMirror(dec_, g);
  }
  ScopedPhase t(timers_, Phase::CouplingInterpolate);
  const CellField* f[6];
  double* out[6];
  for (int d = 0; d < 3; ++d) {
    f[d] = &sampled(uCell_[d], uSmooth_[d]);
    f[3 + d] = &sampled(gradP_[d], gradPSmooth_[d]);
    out[d] = uAt_[d].data();
    out[3 + d] = gradPAt_[d].data();
  }
  interpolate(stencils_, f, out);
}

void Simulation::applyCouplingForces(double dt) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  const std::size_t n = stencils_.count();
  // Co-located, the force goes straight into the DEM's external-force array of the same rank:
  // the hand-over is that store (no copy). Proxies: it waits in the transfer for the message.
  const std::array<double*, 3> out = transfer_->forceTarget();
  // sums: particle drag impulse (3), fluid drag momentum change (3), gross magnitude of the
  // exchanged terms sum beta' (|u| + |v~|) dt (3): the scale of round-off in the balance.
  double sums[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
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
    run_.particleImpulse[d] = sums[d];
    run_.fluidImpulse[d] = sums[3 + d];
    gross = std::max(gross, sums[6 + d]);
    diff = std::max(diff, std::abs(sums[d] + sums[3 + d]));
  }
  if (gross > 0) run_.momentumResidual = std::max(run_.momentumResidual, diff / gross);
}

void Simulation::handForcesToParticles() {
  transfer_->handBack(timers_);
}

void Simulation::advanceParticles(int n) {
  for (int s = 0; s < n; ++s) {
    if (s == n / 2) fault::point("dem", run_.steps + 1);
    dem_->substep();
  }
  run_.substeps += n;
}

// ---- checkpoints (the file format: coupling/checkpoint.hpp) ----------------------------------

void Simulation::writeCheckpoint(const std::string& path, const std::string& status) {
  // The DEM's state first (taken without changing the solver); at a failure the particles as
  // they are if taking it fails.
  std::optional<dem::DemState> demState;
  std::string demSnapshot = "complete";
  if (dem_) {
    if (status == "ok") {
      demState = dem_->saveState();
    } else {
      try {
        demState = dem_->saveState();
      } catch (const Error& e) {
        demState = rawDemState(dem_->particles(), dem_->time(), run_.substeps);
        demSnapshot = std::string("raw (no contact histories): ") + e.what();
      }
    }
  }
  ScopedPhase t(timers_, Phase::Checkpoint);
  const Comm& comm = dec_.comm();
  H5File f = H5File::create(comm, path, /*sync=*/true);
  f.setChecksums(true);  // every dataset carries a Fletcher32 checksum, checked on restart
  f.setAttribute("/", "format", kCheckpointFormat);
  f.setAttribute("/", "version", kCheckpointVersion);
  f.setAttribute("/", "status", status);
  f.setAttribute("/", "case", cfg_.string("name"));
  f.setAttribute("/", "mode", runModeName(mode_));
  f.setAttribute("/", "ranks", comm.size());
  f.setAttribute("/", "step", run_.steps);
  f.setAttribute("/", "time", run_.time);
  f.setAttribute("/", "config", cfg_.json().dump());
  writeGrid(f, dec_.grid());
  writeLayouts(f, layouts_, dec_, demDec_);
  writeRunCounters(f, "/simulation", run_);
  if (fluid_) writeFluidState(f, "/fluid", dec_, std::as_const(*fluid_));
  if (demState) {
    writeDemState(f, "/particles", *demState);
    f.setAttribute("/particles", "snapshot", demSnapshot);
  }
  // Fault point (tests/robustness, coloc_faults only): after the data, before the rename.
  fault::point("checkpoint", run_.steps);
  f.close();
}

Layouts Simulation::restartLayouts(const Comm& world, const Config& cfg,
                                   const std::string& checkpoint) {
  const GlobalGrid grid = gridFromConfig(cfg);
  const CheckpointInfo info = checkRestartable(world, checkpoint, grid, runMode(cfg));
  const std::string strategy = cfg.string("partition.strategy");
  if (info.ranks != world.size() || info.strategy != strategy) return chooseLayouts(world, cfg);
  // The blocks that wrote it: the continuation is then bitwise that of the original run.
  Layouts L{info.fluidBoxLo.empty()
                ? Decomposition::fromCuts(world, grid, info.fluidCuts)
                : Decomposition::fromBoxes(world, grid, info.fluidBoxLo, info.fluidBoxHi),
            std::nullopt,
            strategy,
            CostModel{},
            1.0,
            1.0};
  if (!info.particleCuts[0].empty())
    L.particles = Decomposition::fromCuts(world, grid, info.particleCuts);
  H5File f = H5File::openRead(world, checkpoint);
  readLayoutCosts(f, L);
  f.close();
  return L;
}

void Simulation::writeOutput(OutputWriter& out) {
  if (!out.due(run_.steps)) return;
  ScopedPhase t(timers_, Phase::Output);
  if (fluid_ && out.options().fields) {
    const auto& f = fluid_->fields();
    if (!coupled_) {
      // Fluid-only runs keep no cell-centred velocity; make it for the output.
      if (uCell_[0].layout() != f.p.layout())
        for (auto& u : uCell_) u = CellField(f.p.layout());
      fluid_->cellVelocity(uCell_);
    }
    out.writeFields(run_.steps, run_.time,
                    {OutputField::scalar("p", f.p, "m^2/s^2"),  // kinematic: p / rho
                     OutputField::vector("u", uCell_, "m/s"),
                     OutputField::scalar("eps", f.eps, "1"), OutputField::scalar("K", f.K, "1/s")});
  }
  if (dem_ && out.options().particles) {
    const auto& p = dem_->particles();
    const std::size_t n = p.nOwned;
    // The fluid's force as the DEM integrates it (f_ext, held over the sub-steps; zero without
    // a fluid) and the material: the drag-force field CFD-DEM users look for in ParaView.
    const ParticleExtraColumns extra{true, std::span<const int>(p.material.data(), n),
                                     firstRows(p.fExt, n)};
    out.writeParticles(run_.steps, run_.time, std::span<const std::int64_t>(p.id.data(), n),
                       firstRows(p.x, n), firstRows(p.v, n), firstRows(p.omega, n),
                       std::span<const double>(p.radius.data(), n), extra);
  }
}

Json Simulation::report(double wallSeconds) const {
  const Comm& comm = dec_.comm();
  Json out = timers_.report(comm, wallSeconds);
  const double wall = comm.max(wallSeconds);
  // A tiled layout has no process grid: dims are null and `partition.boxes` lists the boxes.
  const auto dimsJson = [](const Decomposition& d) {
    return d.isTiled() ? Json(nullptr) : Json::array({d.dims()[0], d.dims()[1], d.dims()[2]});
  };
  out["mpi"] = {{"ranks", comm.size()}, {"dims", dimsJson(dec_)}};
  out["run"] = {
      {"mode", runModeName(mode_)}, {"steps", run_.steps}, {"dem_substeps", run_.substeps},
      {"sim_time", run_.time},      {"wall_s", wall},      {"first_step", runStartSteps_}};
  const long long particles = dem_ ? dem_->globalCount() : 0;
  const double cells = static_cast<double>(dec_.grid().cellCount());
  out["throughput"] = {
      {"cell_steps_per_s",
       fluid_ && wall > 0 ? cells * static_cast<double>(run_.steps - runStartSteps_) / wall : 0.0},
      {"particle_steps_per_s",
       dem_ && wall > 0 ? static_cast<double>(particles) *
                              static_cast<double>(run_.substeps - runStartSubsteps_) / wall
                        : 0.0}};
  out["checks"] = {{"momentum_balance", run_.momentumResidual}, {"mass_balance", 0.0}};
  if (fluid_) {
    const Json fd = fluid_->diagnostics();
    for (auto& [k, v] : fd.items()) {
      if (out.contains(k) && out[k].is_object() && v.is_object())
        for (auto& [k2, v2] : v.items()) out[k][k2] = v2;
      else
        out[k] = v;
    }
  }
  if (dem_) out["particles"] = dem_->diagnostics();
  if (dem_) out["checks"]["particle_mass_balance"] = out["particles"]["mass_balance"];
  out["partition"] = {{"strategy", layouts_.strategy},
                      {"fluid_dims", dimsJson(dec_)},
                      {"particle_dims", dimsJson(particleDecomposition())}};
  // Every rank's block, [lo x, y, z, hi x, y, z) in global cells as plan.json writes them (the
  // tiled boxes, or the process grid's blocks): what snapshot.py draws. Independent partitions
  // also give the particles' blocks.
  const auto boxesJson = [](const Decomposition& d) {
    std::vector<Int3> lo, hi;
    d.boxes(lo, hi);
    Json boxes = Json::array();
    for (std::size_t r = 0; r < lo.size(); ++r)
      boxes.push_back(Json::array({lo[r][0], lo[r][1], lo[r][2], hi[r][0], hi[r][1], hi[r][2]}));
    return boxes;
  };
  out["partition"]["boxes"] = boxesJson(dec_);
  if (&particleDecomposition() != &dec_)
    out["partition"]["particle_boxes"] = boxesJson(particleDecomposition());
  if (layouts_.strategy == "balanced" || layouts_.strategy == "tiled")
    out["partition"][layouts_.strategy] = {
        {"cost_per_cell", layouts_.model.perCell},
        {"cost_per_particle", layouts_.model.perParticle},
        {"modelled_imbalance", layouts_.modelledImbalance},
        {"uniform_modelled_imbalance", layouts_.uniformImbalance}};
  if (coupled_)
    out["coupling"] = {{"solid_volume", run_.solidVolume},
                       {"kernel", kernel_ == KernelKind::Centroid ? "centroid" : "trilinear"},
                       {"drag", dragLawName(drag_)}};
  return out;
}

}  // namespace coloc::coupling
