// dem/src/impl.hpp — DemSolver::Impl: the solver composed of its parts. Each part is a small
// struct holding its data (bins.hpp, neighbours.hpp, history.hpp; the particle arrays and their
// field table in coloc/dem/dem.hpp); the methods are defined in the file of their concept. The
// particle exchange is a part that owns its state and works on what Impl lends it
// (exchange.hpp), made once at setup.
//   dem.cpp        the sub-step (velocity Verlet), the rebuild sequence, the public interface
//   setup.cpp      materials, bins, time-step check, initial particles, the exchange
//   flow.cpp       face conditions, outflow removal, inflow insertion, DemFlow
//   history.cpp    contact-history pool: packing into rows per particle, compaction
//   exchange.cpp   the particle exchange: migration, ghost build and update (rows of the field
//                  table), and the migrant rows both layouts share; one implementation per
//                  layout: exchange_grid.cpp (process grid, three sweeps), exchange_tiled.cpp
//                  (general boxes, one exchange each)
//   bins.cpp       the counting sort by bin, the (bin, id) re-sort of owned particles
//   neighbours.cpp  the half Verlet list build (and the history lookup of its entries)
//   forces.cpp     contact and wall forces (the pair law on a chunk: pairs.hpp), contact energy
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
#include "exchange.hpp"
#include "generate.hpp"
#include "history.hpp"
#include "neighbours.hpp"
#include "pairs.hpp"
#include "rows.hpp"

namespace coloc::dem {

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
  Model model = Model::HertzMindlin;
  double dt = 1e-5, time = 0;
  bool frozen = false;
  double g[3] = {0, 0, 0};
  std::vector<Material> mats;
  int nMat = 0;
  std::vector<PairCoeff> pairC;  // [a * nMat + b]
  std::vector<PairCoeff> wallC;  // [a]
  bool rolling = false;          // any material pair with rolling resistance
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
  detail::Bins bins;
  detail::NeighbourList list;
  detail::HistoryPool hist;
  /// Migration, ghost build and update (exchange.hpp): the process grid's or the tiled one,
  /// made at setup (setupBins) from the decomposition.
  std::unique_ptr<detail::ParticleExchange> exchange;
  std::vector<int> inScr;  // scratch (grow-only)
  // the (bin, id) re-sort's permutation, from sortByBin to the end of buildLists (perm[k]: the
  // history row of particle k), in the rebuild's scratch (rebuildInts)
  int* perm = nullptr;
  detail::PairChunk chunk;  // the force loop's touching pairs (pairs.hpp)
  // the force loop's packed particles (pairs.hpp: Body). `packed`: the rows of `body` match
  // the particles (same order and count) since the last force computation, i.e. no rebuild
  // since (rebuild() clears it); the step then keeps them current: initialIntegrate writes the
  // owned bodies and resets the force and torque sums (gravity + fExt) after its half kick.
  // From the start of a rebuild to the next force computation, which packs every body anew,
  // their storage is the rebuild's int scratch (rebuildInts).
  std::vector<detail::Body> body;
  bool packed = false;
  /// `count` ints of scratch in the bodies' storage (grown if needed), valid until the next force
  /// computation; only inside a rebuild (packed is false).
  int* rebuildInts(std::size_t count);

  long long rebuilds = 0, steps = 0;
  // what the last force computation saw (forces.cpp): contacts of owned particles, wall
  // contacts, the largest overlap (fraction of the smaller radius) and its pair
  struct ContactTally {
    long long contacts = 0, walls = 0;
    double maxOverlap = 0;
    std::int64_t maxOverlapId = -1, maxOverlapPartner = 0;
  } tally;

  // dem.cpp: the step
  void substep();
  void initialIntegrate();
  void finalIntegrate();
  bool decideRebuild();
  void rebuild(bool first);
  /// The owned positions as the rebuild check's reference (x0), at the end of a rebuild.
  void keepPositions();
  void checkOverlap(double globalMax);
  std::string where() const;
  std::size_t memory() const;
  /// f(name, bytes) for every part of the solver's storage (capacities): the particle columns
  /// ("fields"), the bins, the list, the history pool, the ghost plans, scratch, the bodies.
  template <class F>
  void memoryParts(F&& f) const {
    f("fields", detail::columnBytes(p));
    f("bins", bins.bytes());
    f("list.rows", detail::cap(list.rowStart));
    f("list.nbr", detail::cap(list.nbr));
    f("list.slot", detail::cap(list.slot));
    f("hist.rows", detail::cap(hist.hStart));
    f("hist.key_x0", detail::cap(hist.hKey));
    f("hist.shear", detail::cap(hist.hS));
    f("hist.free", detail::cap(hist.freeSlots));
    f("ghosts", exchange ? exchange->bytes() : 0);
    f("scratch", detail::cap(inScr));
    f("body", detail::cap(body));
  }
  /// memoryParts as bytes by name (fields by their own names, "field.x" ...).
  Json memoryByPart() const;
  // setup.cpp
  void readMaterials(const Config& cfg);
  void setupBins(const Config& cfg, double dmax, long long total);
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
  void packHistory();
  /// Owned row i kept as row w (w <= i) while rows before it leave (migration, outflow), its
  /// packed contact histories [h0, h1) moved down to hw on.
  void keepRow(std::size_t i, std::size_t w, int h0, int h1, int& hw);
  // bins.cpp, neighbours.cpp
  void sortByBin();
  void buildLists();
  // forces.cpp
  /// Forces at the current state into f and torque; `stepped`: inside the step, where the owned
  /// bodies and the reset sums are current when `packed` (initialIntegrate).
  void computeForces(bool update, bool stepped = false);
  template <Model M, bool Rolling>
  void forces(bool update, bool stepped);
  // state.cpp
  int ownerRank(const double* x) const;
  void restore(DemState& st);
  DemState save();
  DemFlow globalFlow() const;  // collective: the out tallies summed over the ranks
};

}  // namespace coloc::dem
