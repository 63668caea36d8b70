// coloc/coupling/rebalance.hpp — re-balancing the co-located blocks during a run (issue 7).
//
// Every partition.rebalance_interval steps of a balanced run, the cuts are placed anew for the
// particles where they are now, with the cost weights measured by the run itself (busy seconds of
// the fluid phases per cell and of the particle and coupling phases per particle, summed over
// ranks: only their ratio places the cuts). When the modelled largest block cost drops by
// partition.rebalance_threshold or more, the simulation is built anew on the new blocks from the
// old one's state in memory (HDF5 is for restarts only): cells and particles move together (a cell
// and the particles in it land on the same rank, co-location holds by construction), contact
// histories travel with their particles, and the continuation equals the run without re-balancing
// to round-off (the summation order of a few sums changes with the blocks).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "coloc/coupling/simulation.hpp"

namespace coloc::coupling {

struct RebalancePlan {
  std::optional<Layouts> layouts;  // the new blocks; set only when re-balancing pays
  CostModel model;                 // the measured weights
  double currentImbalance = 1.0;   // modelled max/avg block cost of the blocks in use
  double newImbalance = 1.0;       // the same for the new blocks
  double gain = 1.0;               // current / new modelled largest block cost
};

/// The steps between re-balances the case asks for (partition.rebalance_interval in balanced
/// runs; 0: never). Parsed once, before the time loop.
long long rebalanceInterval(const Config& cfg);
/// Whether a re-balance is due after `steps` steps with that interval.
inline bool rebalanceDue(long long every, long long steps) {
  return every > 0 && steps > 0 && steps % every == 0;
}
/// Whether the case asks for a re-balance after `steps` steps (balanced runs only).
bool rebalanceDue(const Config& cfg, long long steps);
/// The new blocks for the particles as they are now. Collective.
RebalancePlan planRebalance(Simulation& sim, const Config& cfg);
/// Moves the run onto `layouts` in memory: the new simulation is built from the old one's state
/// (Simulation(cfg, layouts, from): fields remapped, particles sent to their new owners), then
/// the old one is released; the timers carry over (the move itself booked to the rebalance
/// phase). Collective.
std::unique_ptr<Simulation> applyRebalance(std::unique_ptr<Simulation> sim, const Config& cfg,
                                           Layouts layouts);
/// The same; `scratch` is not written (the name the file path used; kept for its callers).
std::unique_ptr<Simulation> applyRebalance(std::unique_ptr<Simulation> sim, const Config& cfg,
                                           Layouts layouts, const std::string& scratch);
/// The former path, through a restart checkpoint `scratch` (removed afterwards): for comparison
/// (tests, the time of a re-balance before and after). The same state to round-off.
std::unique_ptr<Simulation> applyRebalanceThroughFile(std::unique_ptr<Simulation> sim,
                                                      const Config& cfg, Layouts layouts,
                                                      const std::string& scratch);

}  // namespace coloc::coupling
