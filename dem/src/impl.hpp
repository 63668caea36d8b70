// dem/src/impl.hpp — DemSolver::Impl: the solver composed of its parts. The neighbour search
// (neighbour_search.hpp: bins, half Verlet list, contact-history pool) and the particle exchange
// (exchange.hpp) are parts that own their state and work on what Impl passes or lends them; the
// particle arrays and their field table are in coloc/dem/dem.hpp.
//   dem.cpp        the sub-step (velocity Verlet), the rebuild sequence, the public interface
//   setup.cpp      materials, bins, time-step check, initial particles, the exchange
//   flow.cpp       face conditions, outflow removal, inflow insertion, DemFlow
//   history.cpp    contact-history pool: packing into rows per particle, compaction
//   exchange.cpp   the particle exchange: migration, ghost build and update (rows of the field
//                  table), and the migrant rows both layouts share; one implementation per
//                  layout: exchange_grid.cpp (process grid, three sweeps), exchange_tiled.cpp
//                  (general boxes, one exchange each)
//   bins.cpp       the counting sort by bin, the (bin, id) re-sort of owned particles
//   neighbours.cpp  the half Verlet list build (and the history lookup of its entries), the
//                  rebuild check's reference positions
//   integrator.cpp Integrator (integrator.hpp): velocity Verlet, the half kicks and the drift
//   forces.cpp     ContactForces (contact_forces.hpp): contact and wall forces (the pair law on a
//                  chunk: pairs.hpp), the tally; contact energy
//   heat.cpp       HeatTransfer (heat.hpp): particle temperature, contact conduction
//   state.cpp      save/restore (checkpoints, re-balancing)
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bins.hpp"
#include "buffers.hpp"
#include "coloc/dem/dem.hpp"
#include "contact.hpp"
#include "contact_forces.hpp"
#include "exchange.hpp"
#include "generate.hpp"
#include "heat.hpp"
#include "history.hpp"
#include "integrator.hpp"
#include "neighbour_search.hpp"
#include "neighbours.hpp"
#include "pairs.hpp"
#include "rows.hpp"

namespace coloc::dem {

using detail::ContactLaw;
using detail::ContactTally;
using detail::Material;
using detail::Model;
using detail::PairCoeff;

namespace detail {
/// The condition of a box face (particles.boundary); Open = no wall (particles.walls false).
enum class Face { Wall, Outflow, Periodic, Open };
using FaceKinds = std::array<std::array<Face, 2>, 3>;  // [axis][low, high]
/// particles.boundary resolved against the fluid's periodic axes and the inflow patches
/// (checks.cpp; ConfigError naming the key).
FaceKinds faceKinds(const Config& cfg, const GlobalGrid& grid,
                    const std::vector<InflowInfo>& inflow);
/// particles.materials and particles.wall_material, checked (checks.cpp).
std::vector<Material> readMaterials(const Config& cfg);
/// The time-step check (checks.cpp): particles.dt against particles.dt_fraction of the Rayleigh
/// (Hertz) or collision (linear) time of the smallest particle of each material (infinity: none)
/// and of the inflow's smallest; ConfigError on particles.dt.
struct TimeStepInput {
  double dt, fraction;
  Model model;
  double kn;
  const std::vector<Material>& mats;
  const std::vector<InflowInfo>& inflow;
  const std::vector<double>& rMinOfMaterial;
};
void checkTimeStep(const TimeStepInput& in);
}  // namespace detail

struct DemSolver::Impl {
  Impl(const Decomposition& d, const Config& cfg, Timers& t, DemState* initial = nullptr);

  const Decomposition& dec;
  Comm comm;
  Timers& timers;
  ParticleStore p;

  // physics
  double time = 0;
  bool frozen = false;
  std::vector<Material> mats;
  std::array<std::array<bool, 2>, 3> wallOn{};
  double skin = 0, rc = 0, overlapLimit = 0.2, dtFraction = 0.2;

  // faces and flow (flow.cpp). particles.boundary: the condition of each box face, for every
  // rank (not only the boundary blocks); Open = no wall (particles.walls false): a particle
  // leaving is an error. Every member of `flow` except the out ones is global and identical on
  // every rank (the out ones count this rank's removals).
  using Face = detail::Face;
  std::array<std::array<Face, 2>, 3> face{};
  bool anyOutflow = false;
  std::vector<detail::InflowInfo> inflow;
  DemFlow flow;
  std::int64_t inflowIdBase = 0;
  std::uint64_t seed = 0;
  std::vector<detail::NewParticle> incoming;  // accepted at the step's start, added at its rebuild
  bool forceRebuild = false;

  // the parts
  /// Bins, half Verlet list, contact-history pool and the rebuild's scratch
  /// (neighbour_search.hpp).
  detail::NeighbourSearch search;
  /// Migration, ghost build and update (exchange.hpp): the process grid's or the tiled one,
  /// made at setup (setupBins) from the decomposition.
  std::unique_ptr<detail::ParticleExchange> exchange;
  std::vector<int> inScr;  // scratch (grow-only)
  /// Contact and wall forces: the contact laws, the packed bodies and their protocol, the chunk,
  /// the tally of the last computation (contact_forces.hpp).
  detail::ContactForces forces;
  /// Velocity Verlet: the time step and gravity (integrator.hpp).
  detail::Integrator integrator;
  /// Particle temperature and contact conduction (heat.hpp); off: no fields, no pass.
  detail::HeatTransfer heat;

  long long rebuilds = 0, steps = 0;

  // dem.cpp: the step
  void substep();
  /// A sub-step of frozen particles: with heat on, ghost temperatures, conduction, T.
  void frozenSubstep();
  /// The clock after a sub-step (steps, time).
  void advanceClock();
  /// f() timed as phase ph.
  template <class F>
  decltype(auto) timed(Phase ph, F&& f) {
    ScopedPhase t(timers, ph);
    return f();
  }
  /// The rebuild decision (one allreduce); v2: this rank's largest squared drift velocity of
  /// the sub-step (the inner list's bound, NeighbourSearch::moved).
  bool decideRebuild(double v2);
  void rebuild(bool first);
  void checkOverlap(double globalMax);
  std::string where() const;
  std::size_t memory() const;
  /// f(name, bytes) for every part of the solver's storage (capacities): the particle columns
  /// ("fields"), the bins, the list, the history pool, the ghost plans, scratch, the bodies.
  template <class F>
  void memoryParts(F&& f) const {
    f("fields", detail::columnBytes(p));
    f("bins", search.bins().bytes());
    f("list.rows", detail::cap(search.list().rowStart));
    f("list.nbr", detail::cap(search.list().nbr));
    f("list.slot", detail::cap(search.list().slot));
    f("list.keep", detail::cap(search.list().keep));
    f("hist.rows", detail::cap(search.history().hStart));
    f("hist.key_x0", detail::cap(search.history().hKey));
    f("hist.shear", detail::cap(search.history().hS));
    f("hist.free", detail::cap(search.history().freeSlots));
    f("ghosts", exchange ? exchange->bytes() : 0);
    f("scratch", detail::cap(inScr) + search.scratchBytes());
    f("body", forces.bodyBytes());
  }
  /// memoryParts as bytes by name (fields by their own names, "field.x" ...).
  Json memoryByPart() const;
  // setup.cpp
  void readMaterials(const Config& cfg);
  void setupBins(const Config& cfg, double dmax, long long total);
  /// The sources placed fewer particles than they hold: ConfigError naming the first such
  /// source (collective).
  [[noreturn]] void refuseMissingParticles(const std::vector<detail::SourceInfo>& info);
  void checkTimeStep();
  double massOf(int material, double r) const {
    return mats[static_cast<std::size_t>(material)].density * 4.0 / 3.0 * M_PI * r * r * r;
  }
  void addParticle(const detail::NewParticle& q);
  // flow.cpp
  void setupFaces(const Config& cfg);
  bool beyondOutflow(std::size_t i, int* which) const;
  void removeOutflow();
  void insertInflow();
  // history.cpp
  /// Owned row i kept as row w (w <= i) while rows before it leave (migration, outflow), its
  /// packed contact histories [h0, h1) moved down to hw on.
  void keepRow(std::size_t i, std::size_t w, int h0, int h1, int& hw);
  // forces.cpp
  /// Forces at the current state into f and torque (ContactForces::compute).
  void computeForces(bool update, bool stepped = false);
  // state.cpp
  int ownerRank(const double* x) const;
  void restore(DemState& st);
  /// The energy accounts of a restored state (particles.heat; DemHeat says how).
  void restoreHeat(const DemHeat& a);
  DemState save();
  DemFlow globalFlow() const;  // collective: the out tallies summed over the ranks
};

}  // namespace coloc::dem
