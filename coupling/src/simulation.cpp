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
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

void declareConfig(Schema& s) {
  s.string("coupling.kernel", "trilinear",
           "deposition/interpolation kernel: centroid (PCM) or trilinear (cloud-in-cell)",
           {"centroid", "trilinear"});
  s.string("coupling.drag", "difelice", "drag law: stokes, difelice, gidaspow, beetstra",
           {"stokes", "difelice", "gidaspow", "beetstra"});
  s.number("coupling.eps_min", 0.3, "lower clip of the fluid fraction",
           Range::openClosed(0.0, 1.0));
  s.integer("coupling.smoothing_passes", 0,
            "passes of a conservative diffusion filter (alpha 1/8) on the deposited fields and, "
            "adjointly, on the fields sampled at the particles (0: off)",
            Range::nonNegative());
  s.string("coupling.self_velocity", "none",
           "correction of the self-induced velocity (the particle's own drag reaction in the fluid "
           "it samples): none, or stokeslet (the undisturbed flow of Balachandar, Liu & Lakhote "
           "2019 with this solver's discrete response to the trilinear deposit and its implicit "
           "drag, built up since the run's start; the drag law also sees the fluid fraction "
           "without the particle's own volume and the pressure-gradient force loses the "
           "particle's own share; trilinear kernel, no smoothing, cubic cells; docs/coupling.md)",
           {"none", "stokeslet"});
  s.integer("coupling.dem_substeps", 0,
            "DEM steps per step. coupled, dummy_dem: the CFD step is dem_substeps * particles.dt "
            "(fluid.dt and fluid.adaptive_dt are then not used); 0: the largest whole number of "
            "particles.dt in the fluid's step (fluid.dt, or the adaptive step), at least 1. "
            "particles mode: each step is max(1, dem_substeps) DEM steps (0 means one) and "
            "fluid.dt is ignored",
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
    : Simulation(cfg, chooseLayouts(world, cfg)) {}

namespace {

/// Cost weights measured on the uniform blocks: busy seconds of the fluid phases per cell-step
/// and of the particle and coupling phases per particle-step (summed over ranks).
CostModel calibrate(const Config& cfg, const Decomposition& uniform, long long steps) {
  Layouts probe{uniform, std::nullopt, "uniform", CostModel{}, 1.0, 1.0};
  Simulation sim(cfg, probe);
  for (long long s = 0; s < steps; ++s) sim.step();
  const Comm& comm = uniform.comm();
  double fluid = 0, particles = 0;
  for (std::size_t i = 0; i < kPhases.size(); ++i) {
    const double b = sim.timers().busySeconds(static_cast<Phase>(i));
    if (kPhases[i].category == Category::Fluid) fluid += b;
    if (kPhases[i].category == Category::Particles || kPhases[i].category == Category::Coupling)
      particles += b;
  }
  fluid = comm.sum(fluid);
  particles = comm.sum(particles);
  const double cells = static_cast<double>(uniform.grid().cellCount());
  const double n = sim.particles() ? static_cast<double>(sim.particles()->globalCount()) : 0.0;
  CostModel m;
  m.perCell = fluid / (cells * static_cast<double>(steps));
  m.perParticle = n > 0 ? particles / (n * static_cast<double>(steps)) : 0.0;
  if (!(m.perCell > 0)) m.perCell = 1e-12;
  return m;
}

}  // namespace

StrategyBlocks chooseBlocksOnRoot(const Comm& comm, const std::string& strategy,
                                  const StrategyInput& in, const std::vector<double>& cost,
                                  bool costIsCount) {
  StrategyBlocks b;
  b.strategy = strategy;
  std::string err;
  std::vector<int> packed;
  double imb[2] = {1.0, 1.0};
  if (comm.isRoot()) {
    try {
      b = costIsCount ? chooseBlocks(strategy, in, {}, cost) : chooseBlocks(strategy, in, cost, {});
      for (const Blocks* blk : {&b.fluid, b.particles ? &*b.particles : nullptr}) {
        if (!blk) continue;
        for (int d = 0; d < 3; ++d) packed.push_back(blk->dims[d]);
        for (int d = 0; d < 3; ++d)
          packed.insert(packed.end(), blk->cuts[d].begin(), blk->cuts[d].end());
      }
      imb[0] = b.modelledImbalance;
      imb[1] = b.uniformImbalance;
    } catch (const Error& e) {
      err = e.what();
    }
  }
  err = comm.broadcast(err);
  if (!err.empty()) throw Error(err);
  int len = static_cast<int>(packed.size());
  comm.broadcast(std::span<int>(&len, 1));
  packed.resize(static_cast<std::size_t>(len));
  comm.broadcast(std::span<int>(packed));
  comm.broadcast(std::span<double>(imb, 2));
  if (comm.isRoot()) return b;
  std::size_t q = 0;
  const auto unpack = [&](Blocks& blk) {
    for (int d = 0; d < 3; ++d) blk.dims[d] = packed[q++];
    for (int d = 0; d < 3; ++d) {
      blk.cuts[d].assign(packed.begin() + static_cast<std::ptrdiff_t>(q),
                         packed.begin() + static_cast<std::ptrdiff_t>(q) + blk.dims[d] + 1);
      q += static_cast<std::size_t>(blk.dims[d]) + 1;
    }
  };
  unpack(b.fluid);
  if (q < packed.size()) {
    b.particles.emplace();
    unpack(*b.particles);
  }
  b.modelledImbalance = imb[0];
  b.uniformImbalance = imb[1];
  return b;
}

Layouts Simulation::chooseLayouts(const Comm& world, const Config& cfg) {
  const std::string strategy = cfg.string("partition.strategy");
  if (cfg.integer("partition.rebalance_interval") > 0 && strategy != "balanced")
    throw ConfigError("partition.rebalance_interval",
                      "re-balancing moves the cuts of the balanced strategy: set "
                      "partition.strategy to balanced (it is '" +
                          strategy + "')");
  const Decomposition uniform = decompositionFromConfig(world, cfg);
  Layouts L{uniform, std::nullopt, strategy, CostModel{}, 1.0, 1.0};
  if (strategy == "uniform" || runMode(cfg) == RunMode::FluidOnly) return L;
  const bool independent = strategy == "independent";
  CostModel model{cfg.number("partition.cost.cell"), cfg.number("partition.cost.particle")};
  if (!independent && cfg.integer("partition.calibrate_steps") > 0)
    model = calibrate(cfg, uniform, cfg.integer("partition.calibrate_steps"));
  // Where the particles are: a DEM built on the uniform blocks, only to count them per cell.
  // independent: the DEM's blocks are balanced by particle count.
  // The cost of every cell is gathered on rank 0 only (cellCostsOnRoot), which chooses the blocks
  // and sends them to every rank: no rank but the root holds anything of the global cell count.
  std::vector<double> cost;
  {
    Timers scratch;
    dem::DemSolver probe(uniform, cfg, scratch);
    const auto& p = probe.particles();
    const std::size_t n = p.nOwned;
    cost = cellCostsOnRoot(uniform, std::span<const double>(p.x[0].data(), n),
                           std::span<const double>(p.x[1].data(), n),
                           std::span<const double>(p.x[2].data(), n),
                           independent ? CostModel{0.0, 1.0} : model);
  }
  const StrategyInput in = strategyInput(cfg, world.size());
  const StrategyBlocks b = chooseBlocksOnRoot(world, strategy, in, cost, independent);
  if (independent) {
    L.particles = Decomposition::fromCuts(world, in.grid, b.particles->cuts);
    return L;
  }
  L.fluid = Decomposition::fromCuts(world, in.grid, b.fluid.cuts);
  L.model = model;
  L.modelledImbalance = b.modelledImbalance;
  L.uniformImbalance = b.uniformImbalance;
  return L;
}

StrategyInput strategyInput(const Config& cfg, int ranks) {
  StrategyInput in;
  in.grid = gridFromConfig(cfg);
  in.ranks = ranks;
  const auto dims = cfg.intVec3("partition.dims"), dem = cfg.intVec3("partition.dem_dims");
  for (int d = 0; d < 3; ++d) {
    in.dims[d] = static_cast<int>(dims[d]);
    in.demDims[d] = static_cast<int>(dem[d]);
  }
  in.minCells = minBlockCells(cfg);
  in.granularity = static_cast<int>(std::max<long long>(1, cfg.integer("particles.bin_cells")));
  return in;
}

Simulation::Simulation(const Config& cfg, Layouts layouts)
    : Simulation(cfg, std::move(layouts), nullptr) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, const std::string& checkpoint)
    : Simulation(cfg, std::move(layouts), &checkpoint) {}

Simulation::Simulation(const Config& cfg, Layouts layouts, const std::string* checkpoint)
    : cfg_(cfg),
      layouts_(std::move(layouts)),
      dec_(layouts_.fluid),
      demDec_(layouts_.particles),
      mode_(runMode(cfg)) {
  ScopedPhase setup(timers_, Phase::Setup);
  maxSteps_ = cfg.integer("run.steps");
  steadyTol_ = cfg.number("fluid.steady_tol");
  endTime_ = cfg.number("run.end_time");
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
  }
  fault::point("setup", 0);
  if (mode_ != RunMode::FluidOnly) {
    if (file) {
      dem::DemState state = readDemState(*file, "/particles");
      validateDemState(dec_.comm(), state, dec_.grid(), cfg.at("particles.materials").size(),
                       *checkpoint);
      dem_ =
          std::make_unique<dem::DemSolver>(particleDecomposition(), cfg, timers_, std::move(state));
    } else {
      dem_ = std::make_unique<dem::DemSolver>(particleDecomposition(), cfg, timers_);
    }
    if (mode_ == RunMode::DummyDem) dem_->setFrozen(true);
  }
  if (file) {
    restoreCounters(*file);
    file->close();
  }
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
  eps_ = CellField(layout, 1.0);
  for (int d = 0; d < 3; ++d) {
    uCell_[d] = CellField(layout);
    uCellOld_[d] = CellField(layout);
    gradP_[d] = CellField(layout);
  }
  // Stencils reach one ghost layer: the coupling's halo plan moves (and folds) only that layer
  // of the fluid-layout fields, whatever ghost width the fluid keeps for itself.
  FieldLayout oneLayer = layout;
  oneLayer.ghost = 1;
  halo_ = HaloPlan(dec_, oneLayer);

  if (checkpoint) {
    // What the last step left in the coupling's own fields: eps (with its ghosts), the
    // cell-centred velocity and the pressure gradient of u^{n+1}, p^{n+1}.
    const auto& f = std::as_const(*fluid_).fields();
    forEach(eps_.interior(), [&](int i, int j, int k) { eps_(i, j, k) = f.eps(i, j, k); });
    halo_.gather(eps_);
    fillWallGhostsByMirror(dec_, eps_);
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

void Simulation::beginRun() {
  timers_.beginRun();
  runStartSteps_ = steps_;
  runStartSubsteps_ = substeps_;
}

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
        nSub = std::max<long long>(
            1, static_cast<long long>(std::floor(fluid_->nextDt() / dem_->dt() + 1e-9)));
      const double dt = static_cast<double>(nSub) * dem_->dt();
      waitForSlowestRank();
      gatherParticles();
      computeStencils();
      sampleFluidForDrag();
      evaluateDrag(dt);
      fault::point("coupling", steps_ + 1);
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
      lastDt_ = dt;
      break;
    }
  }
  time_ += lastDt_;
  ++steps_;
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
  const auto& p = dem_->particles();
  const std::size_t n = p.nOwned;
  if (!demDec_) {
    // Co-located: the kernels read the DEM's own arrays.
    view_.n = n;
    for (int d = 0; d < 3; ++d) {
      view_.x[d] = p.x[d].data();
      view_.v[d] = p.v[d].data();
      view_.force[d] = p.f[d].data();
      view_.held[d] = p.fExt[d].data();
    }
    view_.radius = p.radius.data();
    view_.mass = p.mass.data();
    view_.id = p.id.data();
    return;
  }
  // Independent: every particle's coupling data goes to the rank whose fluid block holds it
  // (on one rank the rows stay in memory: an exchange inside the rank).
  ScopedPhase t(timers_, dec_.comm().size() > 1 ? Phase::ExchangeRemote : Phase::ExchangeLocal);
  const double t0 = MPI_Wtime();
  const Comm& comm = dec_.comm();
  const int size = comm.size();
  const auto& g = dec_.grid();
  constexpr int kRow = 12;  // x3 v3 nonDrag3 radius mass id
  auto& X = proxy_;
  X.sendCounts.assign(static_cast<std::size_t>(size), 0);
  if (X.dest.size() < n) X.dest.resize(n + n / 4);
  if (X.order.size() < n) X.order.resize(n + n / 4);
  std::string err;
  for (std::size_t i = 0; i < n; ++i) {
    const int r = dec_.ownerOfPoint({p.x[0][i], p.x[1][i], p.x[2][i]});
    if (r < 0 && err.empty()) err = "particle " + std::to_string(p.id[i]) + " is outside the box";
    X.dest[i] = std::max(r, 0);
    ++X.sendCounts[static_cast<std::size_t>(X.dest[i])];
  }
  comm.raiseIfAny(err);
  Comm::displacements(X.sendCounts, X.sendDispl);
  std::vector<int>& fill = X.recvDispl;  // scratch: next free row per destination
  fill = X.sendDispl;
  for (std::size_t i = 0; i < n; ++i)
    X.order[static_cast<std::size_t>(fill[static_cast<std::size_t>(X.dest[i])]++)] =
        static_cast<int>(i);
  if (X.sendBuf.size() < n * kRow) X.sendBuf.resize(n * kRow + n * kRow / 4);
  for (std::size_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(X.order[k]);
    double* row = X.sendBuf.data() + k * kRow;
    for (int d = 0; d < 3; ++d) {
      double xd = p.x[d][i];
      if (g.periodic[d]) {  // wrap into the box: the fluid owner's block frame
        xd = g.origin[d] + std::fmod(xd - g.origin[d], g.length[d]);
        if (xd < g.origin[d]) xd += g.length[d];
      }
      row[d] = xd;
      row[3 + d] = p.v[d][i];
      row[6 + d] = p.f[d][i] - p.fExt[d][i];
    }
    row[9] = p.radius[i];
    row[10] = p.mass[i];
    row[11] = static_cast<double>(p.id[i]);
  }
  comm.alltoall(X.sendCounts, X.recvCounts);
  for (auto& c : X.sendCounts) c *= kRow;
  for (auto& c : X.recvCounts) c *= kRow;
  Comm::displacements(X.sendCounts, X.sendDispl);
  const int recvTotal = Comm::displacements(X.recvCounts, X.recvDispl);
  if (X.recvBuf.size() < static_cast<std::size_t>(recvTotal))
    X.recvBuf.resize(static_cast<std::size_t>(recvTotal) + recvTotal / 4);
  comm.alltoallv(std::span<const double>(X.sendBuf.data(), n * kRow), X.sendCounts, X.sendDispl,
                 std::span<double>(X.recvBuf.data(), static_cast<std::size_t>(recvTotal)),
                 X.recvCounts, X.recvDispl);
  const std::size_t m = static_cast<std::size_t>(recvTotal / kRow);
  if (X.radius.size() < m) {
    const std::size_t cap = m + m / 4;
    for (int d = 0; d < 3; ++d) {
      X.x[d].resize(cap);
      X.v[d].resize(cap);
      X.nonDrag[d].resize(cap);
    }
    X.radius.resize(cap);
    X.mass.resize(cap);
    X.id.resize(cap);
  }
  for (std::size_t k = 0; k < m; ++k) {
    const double* row = X.recvBuf.data() + k * kRow;
    for (int d = 0; d < 3; ++d) {
      X.x[d][k] = row[d];
      X.v[d][k] = row[3 + d];
      X.nonDrag[d][k] = row[6 + d];
    }
    X.radius[k] = row[9];
    X.mass[k] = row[10];
    X.id[k] = static_cast<std::int64_t>(row[11]);
  }
  view_.n = m;
  for (int d = 0; d < 3; ++d) {
    view_.x[d] = X.x[d].data();
    view_.v[d] = X.v[d].data();
    view_.force[d] = X.nonDrag[d].data();
    view_.held[d] = nullptr;
  }
  view_.radius = X.radius.data();
  view_.mass = X.mass.data();
  view_.id = X.id.data();
  bookProxyTraffic(kRow, MPI_Wtime() - t0);
}

void Simulation::bookProxyTraffic(int valuesPerParticle, double seconds) {
  // Rows to other ranks are messages; the rows a rank keeps for itself move in memory.
  const auto& X = proxy_;
  const int me = dec_.comm().rank();
  long long remote = 0, local = 0, messages = 0;
  for (std::size_t r = 0; r < X.sendCounts.size(); ++r) {
    const long long bytes =
        static_cast<long long>(X.sendCounts[r]) * static_cast<long long>(sizeof(double));
    if (static_cast<int>(r) == me) {
      local += bytes;
    } else if (bytes > 0) {
      remote += bytes;
      ++messages;
    }
  }
  (void)valuesPerParticle;
  // The time goes with the bytes: across ranks when any row left the rank.
  timers_.book(Exchange::InterPhysicsRemote, remote, messages, messages > 0 ? seconds : 0.0,
               Traffic::Proxy);
  timers_.book(Exchange::InterPhysicsLocal, local, 0, messages > 0 ? 0.0 : seconds,
               Traffic::ForceHandover);
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
  for (std::size_t i = 0; i < n; ++i) volume_[i] = 4.0 / 3.0 * kPi * std::pow(view_.radius[i], 3);
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

void Simulation::sampleFluidForDrag() {
  ScopedPhase t(timers_, Phase::CouplingInterpolate);
  interpolate(stencils_, eps_, epsAt_);  // eps = 1 - S(solid) is smooth already
  for (int d = 0; d < 3; ++d) {
    interpolate(stencils_, sampled(uCell_[d], uSmooth_[d]), uAt_[d]);
    interpolate(stencils_, sampled(gradP_[d], gradPSmooth_[d]), gradPAt_[d]);
  }
}

void Simulation::evaluateDrag(double dt) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  const ParticleView& p = view_;
  const std::size_t n = stencils_.count();
  const bool frozen = mode_ == RunMode::DummyDem;
  const bool self = selfVelocity_ != SelfVelocity::None;
  const double vCell = dec_.grid().cellVolume();
  std::string err;
  for (std::size_t i = 0; i < n; ++i) {
    double slip2 = 0;
    for (int d = 0; d < 3; ++d) {
      const double s = uAt_[d][i] - p.v[d][i];
      slip2 += s * s;
    }
    const double epsFluid = std::clamp(epsAt_[i], epsMin_, 1.0);
    // With the correction the drag law sees the undisturbed fluid fraction too: the sampled one
    // less the particle's own volume, deposited and read back with the same weights (its share
    // V / h^3 sum_c w_c^2; self_velocity.hpp).
    double eps = epsFluid;
    if (self) {
      double w2 = volume_[i] / vCell;
      for (int d = 0; d < 3; ++d) {
        const double f = stencils_.fraction(d, i);
        w2 *= (1.0 - f) * (1.0 - f) + f * f;
      }
      eps = std::clamp(epsAt_[i] + w2, epsMin_, 1.0);
    }
    const bool still = frozen || dt <= 0;
    double beta = dragCoefficient(drag_, eps, 2.0 * p.radius[i], std::sqrt(slip2), rhoF_, nu_);
    // 1 + dt beta / m - c beta: the implicit particle response and the self-induced velocity
    // (self_velocity.hpp); c = 0 without the correction.
    double denom = still ? 1.0 : 1.0 + dt * beta / p.mass[i];
    std::array<double, 3> ownPressure{};
    if (self)
      denom = correctForSelfVelocity(i, epsFluid, eps, std::sqrt(slip2), still ? 0.0 : dt,
                                     time_ + std::max(dt, 0.0), beta, ownPressure, err);
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
  if (self) dec_.comm().raiseIfAny(err);
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
    if (drag_ != DragLaw::Stokes)
      beta = dragCoefficient(drag_, epsUndisturbed, d, slipSampled / (1.0 - cb), rhoF_, nu_);
    denom = 1.0 + inertia * beta - c * beta;
    pressure = r.pressure;
  }
  return denom;
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
    depositProduct(stencils_, std::span<const double>(beta_.data(), n),
                   std::span<const double>(vDep_[d].data(), n), s, f.KUp[d]);
}

void Simulation::sumDepositsAcrossBlocks() {
  // Across ranks only when a neighbour block is another rank's. On one rank the sum over a
  // periodic wrap is arithmetic inside the block, like the fold at walls: booked to deposition
  // (so a 1-rank run shows no across-ranks share without bytes).
  ScopedPhase t(timers_, halo_.crossesRanks() ? Phase::ExchangeRemote : Phase::CouplingDeposit);
  auto& f = fluid_->fields();
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
  halo_.gather(eps_, &timers_, Exchange::IntraPhysics, Traffic::CouplingHalo);
  fillWallGhostsByMirror(dec_, eps_);
  fluid_->markCoefficientsChanged();
}

void Simulation::advanceFluid(double dt) {
  fault::point("fluid", steps_ + 1);
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
    interpolate(stencils_, sampled(uCell_[d], uSmooth_[d]), uAt_[d]);
    interpolate(stencils_, sampled(gradP_[d], gradPSmooth_[d]), gradPAt_[d]);
  }
}

void Simulation::applyCouplingForces(double dt) {
  ScopedPhase t(timers_, Phase::CouplingDrag);
  const std::size_t n = stencils_.count();
  // Co-located, the force goes straight into the DEM's external-force array of the same rank:
  // the hand-over is that store (no copy). Independent, it waits in forceAt_ for the message.
  std::array<double*, 3> out{};
  for (int d = 0; d < 3; ++d)
    out[d] = demDec_ ? forceAt_[d].data() : dem_->particles().fExt[d].data();
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
    particleImpulse_[d] = sums[d];
    fluidImpulse_[d] = sums[3 + d];
    gross = std::max(gross, sums[6 + d]);
    diff = std::max(diff, std::abs(sums[d] + sums[3 + d]));
  }
  if (gross > 0) momentumResidual_ = std::max(momentumResidual_, diff / gross);
}

void Simulation::handForcesToParticles() {
  auto& p = dem_->particles();
  if (!demDec_) {
    // Co-located: applyCouplingForces() stored the forces in the DEM's own array; what crossed
    // from one physics to the other is those bytes, in memory, with no copy and no message.
    const std::size_t n = stencils_.count();
    timers_.book(Exchange::InterPhysicsLocal, static_cast<long long>(3 * n * sizeof(double)), 0);
    return;
  }
  // Independent: the forces travel back to the DEM ranks, in the order the rows came.
  ScopedPhase t(timers_, dec_.comm().size() > 1 ? Phase::ExchangeRemote : Phase::ExchangeLocal);
  const double t0 = MPI_Wtime();
  auto& X = proxy_;
  const Comm& comm = dec_.comm();
  constexpr int kRow = 12;
  const std::size_t m = view_.n;
  // Proxy k's force goes back to where its row came from: swap the roles of the counts.
  for (auto& c : X.recvCounts) c = c / kRow * 3;
  for (auto& c : X.sendCounts) c = c / kRow * 3;
  Comm::displacements(X.recvCounts, X.recvDispl);
  Comm::displacements(X.sendCounts, X.sendDispl);
  for (std::size_t k = 0; k < m; ++k)
    for (int d = 0; d < 3; ++d) X.recvBuf[3 * k + static_cast<std::size_t>(d)] = forceAt_[d][k];
  const std::size_t n = p.nOwned;
  comm.alltoallv(std::span<const double>(X.recvBuf.data(), 3 * m), X.recvCounts, X.recvDispl,
                 std::span<double>(X.sendBuf.data(), 3 * n), X.sendCounts, X.sendDispl);
  for (std::size_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(X.order[k]);
    for (int d = 0; d < 3; ++d) p.fExt[d][i] = X.sendBuf[3 * k + static_cast<std::size_t>(d)];
  }
  // Book what this rank sent back (its proxies' forces), by destination.
  std::swap(X.sendCounts, X.recvCounts);
  bookProxyTraffic(3, MPI_Wtime() - t0);
  std::swap(X.sendCounts, X.recvCounts);
}

void Simulation::advanceParticles(int n) {
  for (int s = 0; s < n; ++s) {
    if (s == n / 2) fault::point("dem", steps_ + 1);
    dem_->substep();
  }
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
                    {OutputField::scalar("p", f.p, "m^2/s^2"),  // kinematic: p / rho
                     OutputField::vector("u", uCell_, "m/s"),
                     OutputField::scalar("eps", f.eps, "1"), OutputField::scalar("K", f.K, "1/s")});
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
  out["run"] = {{"mode", runModeName(mode_)}, {"steps", steps_}, {"dem_substeps", substeps_},
                {"sim_time", time_},          {"wall_s", wall},  {"first_step", runStartSteps_}};
  const long long particles = dem_ ? dem_->globalCount() : 0;
  const double cells = static_cast<double>(dec_.grid().cellCount());
  out["throughput"] = {
      {"cell_steps_per_s",
       fluid_ && wall > 0 ? cells * static_cast<double>(steps_ - runStartSteps_) / wall : 0.0},
      {"particle_steps_per_s", dem_ && wall > 0
                                   ? static_cast<double>(particles) *
                                         static_cast<double>(substeps_ - runStartSubsteps_) / wall
                                   : 0.0}};
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
  if (dem_) out["particles"] = dem_->diagnostics();
  if (dem_) out["checks"]["particle_mass_balance"] = out["particles"]["mass_balance"];
  const auto dimsJson = [](const Decomposition& d) {
    return Json::array({d.dims()[0], d.dims()[1], d.dims()[2]});
  };
  out["partition"] = {{"strategy", layouts_.strategy},
                      {"fluid_dims", dimsJson(dec_)},
                      {"particle_dims", dimsJson(particleDecomposition())}};
  if (layouts_.strategy == "balanced")
    out["partition"]["balanced"] = {{"cost_per_cell", layouts_.model.perCell},
                                    {"cost_per_particle", layouts_.model.perParticle},
                                    {"modelled_imbalance", layouts_.modelledImbalance},
                                    {"uniform_modelled_imbalance", layouts_.uniformImbalance}};
  if (coupled_)
    out["coupling"] = {{"solid_volume", solidVolume_},
                       {"kernel", kernel_ == KernelKind::Centroid ? "centroid" : "trilinear"},
                       {"drag", dragLawName(drag_)}};
  return out;
}

}  // namespace coloc::coupling
