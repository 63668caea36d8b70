#include "coloc/coupling/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "coloc/core/error.hpp"
#include "coloc/core/fault.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/coupling/heat_transfer.hpp"
#include "coloc/partition/remap.hpp"
#include "coloc/partition/setup.hpp"
#include "particle_coupling.hpp"

namespace coloc::coupling {

/// Where a new Simulation's state comes from: the case (nothing to read), a checkpoint (the
/// file, opened once it is checked), or a running Simulation on other blocks (re-balance).
struct Simulation::Origin {
  const std::string* checkpoint = nullptr;
  Simulation* running = nullptr;
  std::optional<H5File> file;
  /// Whether the state continues a run (restart or re-balance) rather than the case's start.
  bool continues() const { return checkpoint || running; }
};

Simulation::Simulation(const Comm& world, const Config& cfg)
    : Simulation(cfg, chooseLayouts(world, cfg)) {}

Simulation::Simulation(const Config& cfg, Layouts layouts)
    : Simulation(cfg, std::move(layouts), Origin{}) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, const std::string& checkpoint)
    : Simulation(cfg, std::move(layouts), Origin{&checkpoint, nullptr, std::nullopt}) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, Simulation& from)
    : Simulation(cfg, std::move(layouts), Origin{nullptr, &from, std::nullopt}) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, Origin origin)
    : cfg_(cfg),
      layouts_(std::move(layouts)),
      dec_(layouts_.fluid),
      demDec_(layouts_.particles),
      mode_(runMode(cfg)) {
  ScopedPhase setup(timers_, Phase::Setup);
  readRunLimits();
  openCheckpoint(origin);
  createFluid(origin);
  fault::point("setup", 0);
  createParticles(origin);
  takeRunCounters(origin);
  coupled_ = mode_ == RunMode::Coupled || mode_ == RunMode::DummyDem;
  if (!coupled_) return;
  createCoupling();
  if (origin.continues())
    resumeCoupling();
  else
    initialiseCoupling();
}

void Simulation::readRunLimits() {
  maxSteps_ = cfg_.integer("run.steps");
  steadyTol_ = cfg_.number("fluid.steady_tol");
  endTime_ = cfg_.number("run.end_time");
  demSubsteps_ = cfg_.integer("coupling.dem_substeps");
  timers_.setSyncPoints(cfg_.boolean("run.timer_sync"));
  if (maxSteps_ == 0 && endTime_ <= 0)
    throw ConfigError("run.steps", "give run.steps > 0 or run.end_time > 0");
}

void Simulation::openCheckpoint(Origin& origin) {
  if (!origin.checkpoint) return;
  // Restart: the checkpoint is checked (status, grid, mode) and read on these blocks.
  checkRestartable(dec_.comm(), *origin.checkpoint, dec_.grid(), mode_);
  origin.file.emplace(H5File::openRead(dec_.comm(), *origin.checkpoint));
  fault::point("restart", 0);
}

void Simulation::createFluid(Origin& origin) {
  if (mode_ == RunMode::ParticlesOnly) return;
  fluid_ = std::make_unique<fv::FluidSolver>(dec_, cfg_, timers_);
  if (origin.file) readFluidState(*origin.file, "/fluid", dec_, *fluid_);
  if (origin.running) remapFluid(*origin.running);
}

void Simulation::createParticles(Origin& origin) {
  if (mode_ == RunMode::FluidOnly) return;
  if (origin.file) {
    dem::DemState state = readDemState(*origin.file, "/particles");
    const bool hasT = std::any_of(state.particles.extra.begin(), state.particles.extra.end(),
                                  [](const auto& e) { return e.name == "temperature"; });
    if (cfg_.boolean("particles.heat") && dec_.comm().min(hasT ? 1LL : 0LL) == 0)
      throw ConfigError("particles.heat",
                        "true, but the checkpoint '" + *origin.checkpoint +
                            "' holds no particle temperatures (it was written with "
                            "particles.heat = false): a restart cannot turn the particles' heat "
                            "on; start from the case, or restart with particles.heat = false");
    validateDemState(dec_.comm(), state, dec_.grid(), cfg_.at("particles.materials").size(),
                     *origin.checkpoint);
    dem_ =
        std::make_unique<dem::DemSolver>(particleDecomposition(), cfg_, timers_, std::move(state));
  } else if (origin.running) {
    // The DEM's own restoring constructor sends every row to the owner of its position.
    dem_ = std::make_unique<dem::DemSolver>(particleDecomposition(), cfg_, timers_,
                                            origin.running->dem_->saveState());
  } else {
    dem_ = std::make_unique<dem::DemSolver>(particleDecomposition(), cfg_, timers_);
  }
  if (mode_ == RunMode::DummyDem) dem_->setFrozen(true);
  // Convection (coupled modes): the transfer carries temperatures and heat rates too.
  convects_ = (mode_ == RunMode::Coupled || mode_ == RunMode::DummyDem) &&
              heatLawFromConfig(cfg_) != HeatLaw::None;
  transfer_ = demDec_ ? proxyTransfer(dec_, *dem_, convects_) : colocatedTransfer(*dem_, convects_);
}

void Simulation::takeRunCounters(Origin& origin) {
  if (origin.file) {
    run_ = coupling::readRunCounters(*origin.file, "/simulation");
    origin.file->close();
  }
  if (origin.running) run_ = origin.running->run_;
}

void Simulation::createCoupling() {
  coupling_ = std::make_unique<ParticleCoupling>(cfg_, dec_, timers_, mode_ == RunMode::DummyDem);
  smoothingPasses_ = static_cast<int>(cfg_.integer("coupling.smoothing_passes"));
  const FieldLayout layout = fluid_->fields().p.layout();
  solid_ = CellField(layout);
  scratch_ = CellField(layout);
  eps_ = CellField(layout);
  K_ = CellField(layout);
  for (auto& k : KUp_) k = CellField(layout);
  if (convects_) {
    heatSource_ = CellField(layout);
    heatCoefficient_ = CellField(layout);
  }
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
}

void Simulation::resumeCoupling() {
  // What the last step left in the coupling's own fields: the cell-centred velocity and the
  // pressure gradient of u^{n+1}, p^{n+1} (eps and its ghosts: restored by the fluid).
  fluid_->cellVelocity(uCell_);
  for (auto& u : uCell_) fillWallGhostsByMirror(dec_, u);
  fluid_->pressureGradient(gradP_);
  for (auto& g : gradP_) fillWallGhostsByMirror(dec_, g);
}

void Simulation::initialiseCoupling() {
  // The initial porosity: deposit the particle volume once and start with eps^0 = eps^1 so the
  // first step sees no spurious d(eps)/dt.
  gatherParticles();
  computeStencils();
  evaluateDrag(0.0, nullptr);  // beta is not used yet (K starts at zero)
  depositParticles();
  sumDepositsAcrossBlocks();
  updateFluidCoefficients();
  K_.fill(0.0);
  for (auto& k : KUp_) k.fill(0.0);
  fluid_->startCoupling(fluidInputs());
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
      applyCouplingHeat(dt);
      handForcesToParticles();
      // The heat rates just handed over are the fluid's q dt over these sub-steps: a particle
      // that leaves at an outflow meanwhile takes the rest of its share with it.
      if (convects_) dem_->holdExternalHeat(nSub);
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

void Simulation::gatherParticles() {
  view_ = transfer_->gather(timers_);
}

void Simulation::computeStencils() {
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  coupling_->locate(view_, solid_.layout());
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
  DragFields f{&fluid_->fields().eps};
  for (int d = 0; d < 3; ++d) {
    f[1 + d] = &sampled(uCell_[d], uSmooth_[d]);
    f[4 + d] = &sampled(gradP_[d], gradPSmooth_[d]);
  }
  return f;
}

void Simulation::evaluateDrag(double dt, const DragFields* fields) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  coupling_->evaluateDrag(fields, dt, run_.time);
}

void Simulation::depositParticles() {
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  solid_.fill(0.0);
  K_.fill(0.0);
  for (auto& k : KUp_) k.fill(0.0);
  if (convects_) {
    heatSource_.fill(0.0);
    heatCoefficient_.fill(0.0);
  }
  coupling_->deposit(solid_, K_, {&KUp_[0], &KUp_[1], &KUp_[2]}, convects_ ? &heatSource_ : nullptr,
                     convects_ ? &heatCoefficient_ : nullptr);
}

void Simulation::sumDepositsAcrossBlocks() {
  // Across ranks only when a neighbour block is another rank's. On one rank the sum over a
  // periodic wrap is arithmetic inside the block, like the fold at walls: booked to deposition
  // (so a 1-rank run shows no across-ranks share without bytes).
  ScopedPhase t(timers_, halo_.crossesRanks() ? Phase::ExchangeRemote : Phase::CouplingDeposit);
  Field3<double>* fields[7] = {&solid_,  &K_,          &KUp_[0],         &KUp_[1],
                               &KUp_[2], &heatSource_, &heatCoefficient_};
  const std::span<Field3<double>* const> deposited(fields, convects_ ? 7 : 5);
  halo_.scatterSum(deposited, Fold::Mirror, &timers_, Exchange::InterPhysicsRemote);
  if (smoothingPasses_ > 0) {
    ScopedPhase s(timers_, Phase::CouplingDeposit);
    for (auto* fld : deposited) smoothField(*fld);
  }
}

void Simulation::smoothField(CellField& f) {
  for (int pass = 0; pass < smoothingPasses_; ++pass) smooth(dec_, halo_, f, scratch_);
}

void Simulation::updateFluidCoefficients() {
  // eps^{n+1} on the owned cells, the fluid's input of the step (advanceFluid hands it over;
  // the fluid's step fills its own ghosts).
  ScopedPhase t(timers_, Phase::CouplingDeposit);
  const double epsMin = coupling_->minFluidFraction();
  double solid = 0;
  forEach(solid_.interior(), [&](int i, int j, int k) {
    solid += solid_(i, j, k);
    eps_(i, j, k) = std::clamp(1.0 - solid_(i, j, k), epsMin, 1.0);
  });
  run_.solidVolume = dec_.comm().sum(solid) * dec_.grid().cellVolume();
}

fv::CouplingInputs Simulation::fluidInputs() const {
  return {eps_, K_, KUp_, convects_ ? &heatSource_ : nullptr,
          convects_ ? &heatCoefficient_ : nullptr};
}

void Simulation::advanceFluid(double dt) {
  fault::point("fluid", run_.steps + 1);
  if (coupled_)
    fluid_->step(dt, fluidInputs());
  else
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
  ParticleCoupling::ForceFields f{};
  for (int d = 0; d < 3; ++d) {
    f[d] = &sampled(uCell_[d], uSmooth_[d]);
    f[3 + d] = &sampled(gradP_[d], gradPSmooth_[d]);
  }
  if (convects_) {
    // The step's mean fluid temperature, the one the fluid's implicit exchange saw; its ghosts
    // across blocks from the fluid, mirrored at the box faces (the adjoint of the deposit's fold).
    TMean_ = fluid_->fields().Tmean;
    fillWallGhostsByMirror(dec_, TMean_);
    f[6] = &sampled(TMean_, TSmooth_);
  }
  coupling_->sampleForForces(f);
}

void Simulation::applyCouplingForces(double dt) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  // Co-located, the force goes straight into the DEM's external-force array of the same rank:
  // the hand-over is that store (no copy). Proxies: it waits in the transfer for the message.
  // sums: particle drag impulse (3), fluid drag momentum change (3), gross magnitude of the
  // exchanged terms sum beta' (|u| + |v~|) dt (3): the scale of round-off in the balance.
  double sums[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  coupling_->applyForces(transfer_->forceTarget(), dt, sums);
  // What the fluid lost through its drag term over the step: rho V (K u - K u_p) dt per cell.
  const double rv = coupling_->fluidDensity() * dec_.grid().cellVolume() * dt;
  forEach(solid_.interior(), [&](int i, int j, int k) {
    for (int d = 0; d < 3; ++d)
      sums[3 + d] -= rv * (K_(i, j, k) * uCell_[d](i, j, k) - KUp_[d](i, j, k));
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

void Simulation::applyCouplingHeat(double dt) {
  if (!convects_) return;
  ScopedPhase t(timers_, Phase::CouplingDrag);
  // sums: the heat the particles receive over the step, the gross exchanged heat (the scale of
  // round-off; both from applyHeat), the heat the fluid's cells received (sum H' T_p - sum H'
  // Tmean per cell, what its implicit exchange took).
  // and (sums[3]) the heat exchanged, sum |q| dt, the scale of the energy balance.
  double sums[4] = {0, 0, 0, 0};
  double fromParticles[3] = {0, 0, 0};
  coupling_->applyHeat(transfer_->heatTarget(), dt, fromParticles);
  sums[0] = fromParticles[0];
  sums[1] = fromParticles[1];
  sums[3] = fromParticles[2];
  const CellField& Tmean = fluid_->fields().Tmean;
  forEach(heatSource_.interior(), [&](int i, int j, int k) {
    sums[2] += (heatSource_(i, j, k) - heatCoefficient_(i, j, k) * Tmean(i, j, k)) * dt;
  });
  dec_.comm().sumInPlace(std::span<double>(sums, 4));
  biotMax_ = std::max(biotMax_, dec_.comm().max(coupling_->biotMax()));
  if (sums[1] > 0)
    run_.heatResidual = std::max(run_.heatResidual, std::abs(sums[0] + sums[2]) / sums[1]);
  run_.heatExchanged += sums[3];
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
    std::vector<OutputField> fields = {
        OutputField::scalar("p", f.p, "m^2/s^2"),  // kinematic: p / rho
        OutputField::vector("u", uCell_, "m/s"), OutputField::scalar("eps", f.eps, "1"),
        OutputField::scalar("K", f.K, "1/s")};
    if (fluid_->hasHeat()) fields.push_back(OutputField::scalar("T", f.T, "K"));  // fluid.heat
    out.writeFields(run_.steps, run_.time, fields);
  }
  if (dem_ && out.options().particles) {
    const auto& p = dem_->particles();
    const std::size_t n = p.nOwned;
    // The fluid's force as the DEM integrates it (f_ext, held over the sub-steps; zero without
    // a fluid) and the material: the drag-force field CFD-DEM users look for in ParaView.
    ParticleExtraColumns extra;
    extra.write = true;
    extra.material = std::span<const int>(p.material.data(), n);
    extra.fluidForce = firstRows(p.fExt, n);
    // particles.heat: the temperature field of the table (the same on every rank)
    for (const auto& e : p.extra)
      if (e.name == "temperature") {
        extra.temperature = true;
        extra.temperatureK = std::span<const double>(e.data[0].data(), n);
      }
    out.writeParticles(run_.steps, run_.time, std::span<const std::int64_t>(p.id.data(), n),
                       firstRows(p.x, n), firstRows(p.v, n), firstRows(p.omega, n),
                       std::span<const double>(p.radius.data(), n), extra);
  }
}

double energyBalance(const Json& fluid, const Json& particles, double exchanged) {
  // Fluid and particles together: what the two enthalpies gained equals what came in through
  // the box faces (fluid), the walls (particle contacts) and the particles' inflow and outflow;
  // the convective exchange between them (the fluid's source_heat, the particles' ext_heat_in)
  // is internal and cancels. Relative to the largest of the enthalpies and the gross heat in.
  double faces = 0, gross = 0;
  for (const auto& [face, q] : fluid["face_heat"].items()) {
    faces += q.get<double>();
    gross += std::abs(q.get<double>());
  }
  const double H = fluid["enthalpy"].get<double>() + particles["enthalpy"].get<double>();
  const double H0 =
      fluid["enthalpy_initial"].get<double>() + particles["enthalpy_initial"].get<double>();
  const double wall = particles["wall_heat_in"].get<double>(),
               in = particles["inflow_enthalpy_in"].get<double>(),
               out = particles["outflow_enthalpy_out"].get<double>();
  const double residual = std::abs(H - H0 - (faces + wall + in - out));
  const double scale = exchanged > 0
                           ? exchanged
                           : std::max({std::abs(H), std::abs(H0),
                                       gross + std::abs(wall) + std::abs(in) + std::abs(out)});
  return scale > 0 ? residual / scale : (residual > 0 ? 1.0 : 0.0);
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
  if (out.contains("fluid_heat") && dem_ && out["particles"].contains("heat"))
    out["checks"]["energy_balance"] = energyBalance(out["fluid_heat"], out["particles"]["heat"]);
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
  if (strategyOf(layouts_).balancesCost())
    out["partition"][layouts_.strategy] = {
        {"cost_per_cell", layouts_.model.perCell},
        {"cost_per_particle", layouts_.model.perParticle},
        {"modelled_imbalance", layouts_.modelledImbalance},
        {"uniform_modelled_imbalance", layouts_.uniformImbalance}};
  if (coupled_)
    out["coupling"] = {
        {"solid_volume", run_.solidVolume},
        {"kernel", coupling_->kernel() == KernelKind::Centroid ? "centroid" : "trilinear"},
        {"drag", dragLawName(coupling_->dragLaw())}};
  if (convects_) {
    out["coupling"]["heat_transfer"] = {{"law", heatLawName(coupling_->heatLaw())},
                                        {"biot_max", biotMax_},
                                        {"exchanged", run_.heatExchanged}};
    out["checks"]["heat_exchange_balance"] = run_.heatResidual;
    // The same residual as energy_balance, relative to the heat the two phases exchanged (not to
    // their enthalpies, hundreds of K above the changes): a leak of 1e-9 of the exchange shows.
    if (out.contains("fluid_heat") && out["particles"].contains("heat"))
      out["checks"]["energy_balance_exchanged"] =
          energyBalance(out["fluid_heat"], out["particles"]["heat"], run_.heatExchanged);
  }
  return out;
}

}  // namespace coloc::coupling
