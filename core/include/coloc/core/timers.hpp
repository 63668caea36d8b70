// coloc/core/timers.hpp — one table of phase names; wall and thread-CPU (busy) time per phase,
// reduced to min/avg/max over ranks for the report. Exchange accounting by the three kinds of
// exchange (docs/architecture.md) lives here too, so every folder books its messages in one place.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"

namespace coloc {

/// What a phase counts towards in `fractions.*`.
enum class Category : std::uint8_t {
  Setup,
  Fluid,
  Particles,
  Coupling,
  InterPhysics,
  Output,
  Wait,  // waiting for the slowest rank: load imbalance, not data movement
  Count
};

enum class Phase : std::uint8_t {
  Setup,
  // fv: one fluid step
  FluidMomentum,          // convection, diffusion, body force, drag: the predictor u*
  FluidBoundary,          // boundary conditions on the fields
  FluidHalo,              // intra-physics halo exchanges of the fluid
  FluidPressureAssemble,  // matrix and right-hand side of the pressure equation
  FluidPressureSetup,     // hypre's multigrid and PCG set-up on a new matrix (not every step)
  FluidPressureSolve,     // hypre PCG+PFMG
  FluidProject,           // velocity correction
  FluidCellFields,        // cell-centred velocity and pressure gradient the coupling samples
  // dem: one sub-step
  DemNeighbour,  // binning, sorting, Verlet lists
  DemForce,      // contact and wall forces
  DemIntegrate,  // velocity Verlet
  DemGhost,      // ghost update (intra-physics)
  DemMigrate,    // migration at rebuilds (intra-physics)
  // coupling arithmetic (not exchange)
  CouplingDeposit,      // kernel weights: particles -> eps, K, K u_p
  CouplingInterpolate,  // kernel weights: u, eps, grad p -> particles
  CouplingDrag,         // drag laws
  // inter-physics exchange (data movement between the two physics)
  ExchangeLocal,   // inside a rank: gather/scatter between fluid and particle structures
  ExchangeRemote,  // across ranks: reverse halo sum of deposited fields, independent-mode transfers
  Sync,            // a timed barrier before the first exchange after the DEM sub-steps
  Output,
  Checkpoint,
  Rebalance,  // moving cells and particles onto new blocks (partition.rebalance_interval)
  Count
};

struct PhaseInfo {
  std::string_view name;
  Category category;
  bool compute = true;  // counted in the busy time (load.*): false for phases that mostly wait
};

inline constexpr std::array<PhaseInfo, static_cast<std::size_t>(Phase::Count)> kPhases = {{
    {"setup", Category::Setup},
    {"fluid_momentum", Category::Fluid},
    {"fluid_boundary", Category::Fluid},
    {"fluid_halo", Category::Fluid, false},
    {"fluid_pressure_assemble", Category::Fluid},
    {"fluid_pressure_setup", Category::Fluid},
    {"fluid_pressure_solve", Category::Fluid},
    {"fluid_project", Category::Fluid},
    {"fluid_cell_fields", Category::Fluid},
    {"dem_neighbor", Category::Particles},
    {"dem_force", Category::Particles},
    {"dem_integrate", Category::Particles},
    {"dem_ghost", Category::Particles, false},
    {"dem_migrate", Category::Particles, false},
    {"coupling_deposit", Category::Coupling},
    {"coupling_interpolate", Category::Coupling},
    {"coupling_drag", Category::Coupling},
    {"exchange_local", Category::InterPhysics, false},
    {"exchange_remote", Category::InterPhysics, false},
    {"sync", Category::Wait, false},
    {"output", Category::Output},
    {"checkpoint", Category::Output},
    {"rebalance", Category::Setup},
}};

inline constexpr std::string_view phaseName(Phase p) {
  return kPhases[static_cast<std::size_t>(p)].name;
}

/// The three kinds of exchange (docs/architecture.md).
enum class Exchange : std::uint8_t { IntraPhysics, InterPhysicsLocal, InterPhysicsRemote, Count };
inline constexpr std::array<std::string_view, 3> kExchangeNames = {
    "intra_physics", "inter_physics_local", "inter_physics_remote"};

/// Finer kinds of traffic inside those three, one counter each (exchange_kinds.* in the report):
/// what `coloc plan` predicts per kind. Auto: the default of the exchange kind (intra-physics ->
/// fluid_halo, inter-physics remote -> deposit_sum, inter-physics local -> force_handover).
enum class Traffic : std::uint8_t {
  FluidHalo,      // the fluid solver's own halo gathers
  CouplingHalo,   // the coupling's one-layer gather of eps
  DemGhost,       // DEM ghost build and ghost updates
  DemMigrate,     // DEM migration at neighbour rebuilds
  DepositSum,     // reverse halo sum of the deposited fields
  Proxy,          // independent strategy: particle rows to the fluid ranks and forces back
  ForceHandover,  // inter-physics local: bytes that cross between the physics inside a rank
  Count,
  Auto = Count
};
inline constexpr std::array<std::string_view, 7> kTrafficNames = {
    "fluid_halo",  "coupling_halo", "dem_ghost",     "dem_migrate",
    "deposit_sum", "proxy",         "force_handover"};

double threadCpuSeconds();

/// Phases nest exclusively: starting a phase inside another pauses the outer one until the inner
/// one stops, so every moment is booked to exactly one phase and the fractions add up.
class Timers {
 public:
  void start(Phase p);
  void stop(Phase p);
  /// Seconds and calls of a phase on this rank.
  double seconds(Phase p) const { return slot(p).wall; }
  double busySeconds(Phase p) const { return slot(p).cpu; }
  long long calls(Phase p) const { return slot(p).calls; }
  /// Timed barriers at the solvers' sync points (`run.timer_sync`, like LAMMPS's `timer sync`):
  /// off by default. When on, syncPoint() waits for every rank of `comm` and books the wait to
  /// `sync`, so that the load imbalance of the work before it is not booked to the collective
  /// phase that follows (a halo exchange, the DEM's rebuild vote). Every rank must reach the
  /// same sync points in the same order: the solvers call it where all ranks do.
  void setSyncPoints(bool on) { syncPoints_ = on; }
  void syncPoint(const Comm& comm);
  /// Adds one interval measured outside start/stop (e.g. across objects' lifetimes).
  void add(Phase p, double wallSeconds, double cpuSeconds);
  /// Book one exchange: bytes and messages sent by this rank, and its time.
  void book(Exchange kind, long long bytes, long long messages, double seconds = 0.0,
            Traffic traffic = Traffic::Auto);
  long long bytes(Traffic t) const { return traffic_[static_cast<std::size_t>(t)].bytes; }
  long long messages(Traffic t) const { return traffic_[static_cast<std::size_t>(t)].messages; }
  long long bytes(Exchange kind) const { return ledger_[idx(kind)].bytes; }
  long long messages(Exchange kind) const { return ledger_[idx(kind)].messages; }
  void reset();
  /// Start of the time loop: forget what the phases and the ledger gathered during set-up
  /// (the Setup phase itself is kept), so fractions and calls describe the steps only.
  void beginRun();

  /// Collective: timers.<phase>.{min,avg,max,calls,busy_max,busy_avg},
  /// exchange.<kind>.{bytes,messages,time_s}, exchange_kinds.<traffic>.{bytes,messages,
  /// bytes_max,messages_max}, fractions.*, load_imbalance.
  Json report(const Comm& comm, double stepWallSeconds) const;

 private:
  struct Slot {
    double wall = 0, cpu = 0, wall0 = 0, cpu0 = 0;
    long long calls = 0;
    int depth = 0;  // a phase started inside itself counts once (the outermost interval)
  };
  struct Ledger {
    long long bytes = 0, messages = 0;
    double seconds = 0;
  };
  static std::size_t idx(Phase p) { return static_cast<std::size_t>(p); }
  static std::size_t idx(Exchange e) { return static_cast<std::size_t>(e); }
  const Slot& slot(Phase p) const { return slots_[idx(p)]; }
  std::array<Slot, static_cast<std::size_t>(Phase::Count)> slots_{};
  std::array<Ledger, static_cast<std::size_t>(Exchange::Count)> ledger_{};
  std::array<Ledger, static_cast<std::size_t>(Traffic::Count)> traffic_{};
  std::array<Phase, 16> active_{};  // the running phases, innermost last
  int nActive_ = 0;
  bool syncPoints_ = false;
};

/// RAII phase timer: `ScopedPhase t(timers, Phase::DemForce);`
class ScopedPhase {
 public:
  ScopedPhase(Timers& t, Phase p) : t_(t), p_(p) { t_.start(p_); }
  ~ScopedPhase() { t_.stop(p_); }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  Timers& t_;
  Phase p_;
};

/// Peak resident set size of this process in bytes (getrusage).
long long peakRssBytes();

}  // namespace coloc
