// coloc/dem/dem.hpp — the linked-cell soft-sphere DEM (docs/dem.md).
//
// Contract with coupling/ (do not change without changing the coupling):
//  - particles() holds owned particles in [0, nOwned) followed by ghosts; SoA arrays.
//  - the coupling writes an external force per owned particle into fExt (N), held constant
//    over the sub-steps until written again; it reads x, v, radius of owned particles.
//    Owned particles may sit up to skin/2 outside the block between neighbour rebuilds.
//  - with particles.heat (docs/heat.md, "Particles"), the store has the extra fields "temperature"
//    (K; kept current on ghosts), "heat_rate" (W; the contact conduction of the last force
//    computation) and "heat_ext" (W): the coupling writes an external heat rate per owned
//    particle into heat_ext, held constant over the sub-steps until written again, exactly as
//    fExt; it reads temperature of owned particles. Without particles.heat none of them exists.
//  - setFrozen(true) is the paper's DummyDEM: particles never move and have no contacts, the
//    coupling still does every exchange.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/dem/fields.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc::dem {

/// Declares the "particles.*" keys of the case file.
void declareConfig(Schema& s);

/// Structure of arrays; owned particles first, then ghosts. Every array is an entry of the field
/// table (forEachField below), which says where it travels.
struct ParticleStore {
  std::size_t nOwned = 0, nGhost = 0;
  std::vector<std::int64_t> id;
  std::vector<int> material;
  std::array<std::vector<double>, 3> x, v, omega, f, torque, fExt;
  std::vector<double> radius, mass;
  std::vector<ExtraField> extra;  // quantities registered with addField
  std::size_t size() const { return nOwned + nGhost; }
  /// Registers a per-particle quantity of 1 or 3 doubles travelling in `ops` (FieldOp bits), zero
  /// for the rows present; returns its index in `extra`. Collective in effect: every rank
  /// registers the same fields in the same order (a DemState that carries extra fields passes
  /// them on to the solver it restores). Throws coloc::Error on a duplicate or bad entry.
  std::size_t addField(const std::string& name, int components, unsigned ops);
  /// Component `component` of the extra field `name` (throws coloc::Error if none).
  std::vector<double>& field(std::string_view name, int component = 0);
  const std::vector<double>& field(std::string_view name, int component = 0) const;
};

/// The field table: f(FieldInfo, columns) for every per-particle array of `p` (ParticleStore,
/// const or not), where `columns` points to `components` std::vector<T> (T = std::int64_t, int or
/// double): the built-in members, then the extra fields. A built-in field is one member above
/// and one line here; packing, sorting, resizing, DemState and checkpoint files follow.
template <class Store, class F>
void forEachField(Store& p, F&& f) {
  constexpr unsigned kGhost = kOpGhostBuild | kOpMigrate | kOpState;  // fixed per particle
  constexpr unsigned kMoving = kGhost | kOpGhostUpdate;               // refreshed every step
  f(FieldInfo{"id", 1, kGhost}, &p.id);
  f(FieldInfo{"material", 1, kGhost}, &p.material);
  f(FieldInfo{"x", 3, kMoving | kOpPosition}, p.x.data());
  f(FieldInfo{"v", 3, kMoving}, p.v.data());
  f(FieldInfo{"omega", 3, kMoving}, p.omega.data());
  f(FieldInfo{"f", 3, kOpState}, p.f.data());
  f(FieldInfo{"torque", 3, kOpState}, p.torque.data());
  f(FieldInfo{"f_ext", 3, kOpMigrate | kOpState}, p.fExt.data());  // held over the sub-steps
  f(FieldInfo{"radius", 1, kGhost}, &p.radius);
  f(FieldInfo{"mass", 1, kGhost}, &p.mass);
  for (auto& e : p.extra) f(FieldInfo{e.name, e.components, e.ops, true}, e.data.data());
}

/// Doubles a row of operation `op` (a FieldOp bit) carries a particle: the sum of the components
/// of the fields of `p` in `op` (a default ParticleStore: the built-in fields). What the DEM's
/// exchanges send, and what coloc plan counts.
std::size_t rowWidth(const ParticleStore& p, unsigned op);

/// The owned rows of every field in kOpState (nGhost = 0): what a DemState holds.
ParticleStore ownedRows(const ParticleStore& p);

/// One pair's tangential (and, where the model keeps one, rolling) history, keyed by global ids.
/// `holder` is the particle that carries the record (it migrates with that particle).
struct ContactHistory {
  std::int64_t holder = 0, partner = 0;
  std::array<double, 3> shear{}, roll{};
};

/// Particles that entered and left (particles.inflow, outflow faces), global totals.
struct DemFlow {
  long long countInitial = 0, countIn = 0, countOut = 0;
  double massInitial = 0, massIn = 0, massOut = 0;
  std::array<long long, 6> countOutByFace{};    // xlo, xhi, ylo, yhi, zlo, zhi
  std::vector<long long> due, inserted;         // per inflow source: particles due, inserted
  std::vector<double> dueMass;                  // per inflow source: mass of the particles due
  std::vector<std::vector<long long>> waiting;  // per inflow source: due, not yet inserted
  /// As numbers (checkpoint files) and back.
  std::vector<double> pack() const;
  static DemFlow unpack(const std::vector<double>& v);
};

/// The particles' energy accounts (particles.heat; docs/heat.md, "Particles"), J. In the states
/// of a run's ranks the global ones are the same in every state and the shares add up over the
/// states to the run's totals: a restore on any rank count keeps each share once (a rank keeps
/// the shares of the state it passes), so the report's sums are unchanged, and on the same
/// ranks every rank continues its own share bit for bit.
struct DemHeat {
  bool known = false;            // false: none (particles.heat off, or a file from before them)
  double enthalpyInitial = 0;    // global: the particles' enthalpy when the run started
  double inflowIn = 0;           // global: enthalpy brought by the inflow sources
  double wallIn = 0, extIn = 0;  // shares: heat in through the walls, from heat_ext
  double outflowOut = 0;         // share: enthalpy of the particles removed at outflow faces
};

/// The complete restartable state of one rank's owned particles (checkpoint/restart and
/// re-balancing). particles holds owned particles only (nGhost = 0): every field of the table in
/// kOpState (with f, torque and fExt, and the extra fields registered with kOpState).
struct DemState {
  ParticleStore particles;
  std::vector<ContactHistory> contacts;  // every history held by an owned particle
  /// In memory only: the row in `particles` of each contact's holder (saveState fills it). A
  /// state with it moves each history along with its holder in one exchange; without it (read
  /// from a file, or edited) the histories find their holders through a directory by id.
  std::vector<int> contactRow;
  /// Each particle's position at the last neighbour rebuild (row for row with `particles`): the
  /// position its rank, bin order, ghosts and Verlet list were built from, and the reference of
  /// the rebuild check. A restore rebuilds there and then moves the particles to `x`, so the
  /// restored run continues exactly as the one that saved. Empty (a file without it): taken as x.
  std::array<std::vector<double>, 3> xRebuild;
  double time = 0;
  long long steps = 0, rebuilds = 0;
  DemFlow flow;  // the same on every rank
  DemHeat heat;  // particles.heat: the energy accounts
};

/// The DEM's bins for blocks with these cuts (the rule every DemSolver applies:
/// particles.bin_cells, particles.bin_split, or automatic: bins of whole cells holding the
/// interaction range dmax + skin, or cells split into bins near that range). Throws ConfigError
/// naming the key.
struct BinLayout {
  std::array<double, 3> size{};  // bin edge (m)
  std::array<long long, 3> split{1, 1, 1}, multiple{1, 1, 1}, globalBins{1, 1, 1};
  /// First global bin of a block starting at cell c.
  long long blockBinLo(int d, int c) const {
    return split[d] > 1 ? 1LL * c * split[d] : c / multiple[d];
  }
  /// Physical bounds of a block's bins [binLo, binHi) (the last ends exactly at the box face).
  double lo(const GlobalGrid& g, int d, long long binLo) const {
    return g.origin[d] + static_cast<double>(binLo) * size[d];
  }
  double hi(const GlobalGrid& g, int d, long long binHi) const {
    return binHi == globalBins[d] ? g.origin[d] + g.length[d]
                                  : g.origin[d] + static_cast<double>(binHi) * size[d];
  }
  /// Global bin of a coordinate, clamped into the box (the DEM's owner rule).
  long long binOf(const GlobalGrid& g, int d, double x) const {
    const double s = std::floor((x - g.origin[d]) / size[d]);
    long long b = !(s > -1e15)  ? -(1LL << 50)
                  : !(s < 1e15) ? (1LL << 50)
                                : static_cast<long long>(s);
    return std::clamp(b, 0LL, globalBins[d] - 1);
  }
  /// The cell whose block owns a global bin.
  int cellOfBin(int d, long long b) const {
    return static_cast<int>(split[d] > 1 ? b / split[d] : b * multiple[d]);
  }
};
BinLayout binLayout(const Config& cfg, const GlobalGrid& grid,
                    const std::array<std::vector<int>, 3>& cuts, double dmax, double skin,
                    long long total);

/// Every particle of the case as a run creates it (the same generator and sources, whatever the
/// rank count), without building a solver: centres, and the sizes the bins follow; with `rows`
/// also each particle's radius and global id (checkCase's overlap check). For `coloc plan` and
/// `coloc check`, which lay them out for rank counts they do not run.
struct CaseParticles {
  std::array<std::vector<double>, 3> x;
  std::vector<double> radius;            // with rows only
  std::vector<std::int64_t> id;          // with rows only
  double dmax = 0, skin = 0, range = 0;  // largest diameter, skin, interaction range (m)
  double rMin = 0, rMax = 0;             // smallest, largest radius generated (0: none)
  std::vector<double> rMinOfMaterial;    // smallest radius of each material (inf: none)
  long long total = 0;
};
CaseParticles caseParticles(const Config& cfg, const GlobalGrid& grid, bool rows = false);

/// The DEM's checks of a case, without a solver (`coloc check`), in the order a DemSolver's
/// construction makes them and with the same functions and messages: materials, sources, inflow,
/// face conditions, bins (one block; a run's blocks are checked as it builds them), the time
/// step against the smallest particle of each material (particles.dt_fraction), and, where
/// `particles` holds rows, the largest initial overlap against particles.overlap_limit. Throws
/// ConfigError naming the key (coloc::Error for an overlap).
void checkCase(const Config& cfg, const GlobalGrid& grid, const CaseParticles& particles);

class DemSolver {
 public:
  DemSolver(const Decomposition& dec, const Config& cfg, Timers& timers);
  /// Restart / re-balance: the particles and histories of `initial` instead of generating them
  /// from the case (each rank may pass any subset; particles are sent to their owners). Collective.
  DemSolver(const Decomposition& dec, const Config& cfg, Timers& timers, DemState initial);
  ~DemSolver();
  DemSolver(const DemSolver&) = delete;
  DemSolver& operator=(const DemSolver&) = delete;

  ParticleStore& particles();
  const ParticleStore& particles() const;
  /// One DEM step of dt(): forces, velocity Verlet, ghosts, rebuild/migration when needed.
  void substep();
  double dt() const;
  double time() const;
  void setFrozen(bool frozen);
  /// particles.heat: the external heat rates just written into `heat_ext` are meant for the next
  /// `substeps` sub-steps (one CFD step of the coupling, which charged the fluid q dt for each
  /// particle). A particle removed at an outflow face before they have passed takes the heat of
  /// the sub-steps it did not see with it: its outflow enthalpy and ext_heat_in count q times
  /// the time left, so that the particles receive exactly what the fluid gave (docs/heat.md,
  /// "Energy accounts"). 0 (the default): heat_ext is held without an end, as written.
  void holdExternalHeat(long long substeps);
  long long globalCount() const;  // collective
  /// Report entries: particles.{count,contacts_per_particle,rebuilds,...}. Collective.
  Json diagnostics() const;

  // Additions beyond the coupling contract (tests, benchmarks, reports).
  /// The complete state, taken without changing the solver (no rebuild, no migration): the run
  /// that saved it continues exactly as if it had not, and a solver restored from it on the same
  /// blocks continues bitwise identically (on other blocks to round-off). Collective.
  DemState saveState();
  /// Forces a neighbour rebuild now: migration, re-sort by bin, ghosts, Verlet lists. Collective.
  void rebuildNow();
  /// Recomputes the forces at the current state without advancing the contact history.
  void computeForcesNow();
  /// Elastic energy stored in the normal springs of all contacts (J). Collective.
  double contactEnergy() const;
  /// Largest diameter + skin (m), the skin (m), the bin edge along each axis (m).
  double interactionRange() const;
  double skin() const;
  std::array<double, 3> binSize() const;
  /// Neighbour rebuilds since construction (the construction's own build not counted).
  long long rebuildCount() const;
  /// Bytes held by this rank's particle structures (arrays, lists, bins, buffers: capacities).
  std::size_t memoryBytes() const;
  /// Touching particle-particle contacts seen by this rank's owned particles in the last force
  /// computation (each contact counted once per owned partner), and particle-wall contacts.
  long long localContacts() const;
  long long localWallContacts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace coloc::dem
