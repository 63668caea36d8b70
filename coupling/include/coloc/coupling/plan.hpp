// coloc/coupling/plan.hpp — what a run on N ranks would own and send, without running it.
//
// planLayout() partitions the case's particles (dem::caseParticles: the run's own generator) with
// the blocks a strategy chooses for N ranks (partition/strategy.hpp: the run's own code path),
// and counts per rank what one coupling step books in the exchange ledger (Timers, by Traffic
// kind): the fluid's halo gathers (eps among them: the coupling reads the fluid's eps), the
// reverse sum of the deposits, the DEM ghost updates of every sub-step, the independent strategy's
// proxies and the in-rank force hand-over. The halo schedule of a step (which gathers, how many
// fields) mirrors fv::FluidSolver::step and Simulation::step; the exactness test (tests/coupling/
// test_plan_exact.cpp) compares it with the ledger of real runs, kind by kind.
//
// A layout of tiled boxes (partition/tiled.hpp) is counted as the general box halo (partition/
// box_halo.hpp: one message per neighbour box, pieces of the ghost region) and DEM ghosts sent to
// every box within the interaction range send, with the same halo schedule per step
// (tests/coupling/test_plan_tiled.cpp checks the halo part against BoxHaloPlan's ledger).
//
// Not modelled per step: DEM migration and ghost rebuilds (they follow the particles' motion;
// a first step from rest has none), hypre's own messages inside the pressure solve, collectives.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc::coupling {

inline constexpr std::size_t kTrafficKinds = static_cast<std::size_t>(Traffic::Count);

struct TrafficCount {
  long long bytes = 0, messages = 0;
};

struct RankPlan {
  long long cells = 0;       // owned fluid cells
  long long particles = 0;   // owned DEM particles
  long long proxies = 0;     // independent: particles whose cell this rank's fluid block holds
  long long ghostCells = 0;  // cells received by one gather of one cell field (2 layers)
  long long demGhosts = 0;   // DEM ghost particles (received at a ghost build)
  double cost = 0;           // modelled cost: partition.cost.cell x cells + .particle x particles
  int haloNeighbours = 0;    // tiled: ranks one gather of a 2-layer cell field receives from
  std::array<TrafficCount, kTrafficKinds> perStep{};  // what this rank books in one step
};

struct LayoutPlan {
  std::string strategy;
  int ranks = 0;
  Blocks fluid, particles;         // particles == fluid unless independent (empty for tiled)
  std::vector<IndexBox> boxes;     // tiled: rank r's box of cells (both physics)
  double modelledImbalance = 1.0;  // tiled: max/mean of the cost the bisection balanced
  double imbalanceFloor = 0.0;  // tiled: boxCostFloor / mean (no layout of legal boxes does better)
  long long substeps = 0;       // DEM sub-steps per coupling step that exchange ghosts
  double imbalance = 1.0;       // max / mean of RankPlan::cost
  std::vector<RankPlan> rank;
  std::string error;  // set when the strategy has no legal layout for this rank count
};

/// The inputs shared by every rank count of one case.
struct PlanCase {
  const Config* cfg = nullptr;
  GlobalGrid grid;
  RunMode mode = RunMode::Coupled;
  dem::CaseParticles particles;
  std::vector<double> cost, count;  // per global cell: modelled cost, particles
};
PlanCase planCase(const Config& cfg);

/// The layout `strategy` would choose on `ranks` ranks (PartitionStrategy::layoutFor: a fluid-only
/// case keeps the start layout, as a run does) and its per-rank work and traffic. Errors of the
/// layout (no legal grid, bins that do not fit) land in LayoutPlan::error.
LayoutPlan planLayout(const PlanCase& pc, const PartitionStrategy& strategy, int ranks);
/// The same for the strategy called `strategy` (ConfigError when there is none).
LayoutPlan planLayout(const PlanCase& pc, const std::string& strategy, int ranks);

}  // namespace coloc::coupling
