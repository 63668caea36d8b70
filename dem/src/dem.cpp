// dem/src/dem.cpp — the linked-cell soft-sphere DEM on the shared decomposition.
//
// One sub-step (velocity Verlet, as LAMMPS/LIGGGHTS run it):
//   1. v += dt/2 F/m, x += dt v, omega += dt/2 T/I                     (DemIntegrate)
//   2. one allreduce: largest displacement since the last rebuild and largest overlap
//      -> rebuild when any particle moved more than skin/2            (DemNeighbor)
//   3. rebuild: contact history packed per particle, migration in three sweeps x, y, z
//      (DemMigrate); owned particles re-sorted by (bin, id) (DemNeighbor); ghosts within the
//      interaction range of every block face in three sweeps x, y, z, so edges and corners are
//      covered, periodic faces shift positions by the box length (DemGhost); bins and Verlet
//      lists (DemNeighbor).  Otherwise: ghost positions/velocities refreshed along the same
//      send lists (DemGhost).
//   4. forces: gravity + fExt + contacts + walls                        (DemForce)
//   5. v += dt/2 F/m, omega += dt/2 T/I                                 (DemIntegrate)
//
// Determinism across rank counts. The Verlet list is a half list with Newton's third law inside
// the rank (an owned-ghost pair is computed by each rank for its own particle, so nothing goes
// back to a ghost's owner). Every local particle has a canonical key K = (global bin in (z, y, x)
// order, unwrapped across periodic faces; global id); holders are visited in K order and list
// their partners of larger K in increasing K, and a pair is always computed with the lower-K
// particle first. A particle therefore receives the same terms in the same order at any rank
// count (lower-K partners, then its own row, then walls), and trajectories agree bit for bit
// between 1, 2 and 4 ranks (what the serial-vs-parallel test checks, with the 1e-10 bound of the
// issue). The tangential history lives in a pool of touching pairs only; at a rebuild it becomes
// rows per owned particle keyed by the partner's global id, which travel with the particle.
//
// Ownership follows the bins: a particle belongs to the rank whose bins contain
// floor((x - origin)/bin) along each axis (clamped into the box). Bin edges coincide with CFD
// cell edges (a bin is k cells or 1/k cell), so block edges are bin edges.
#include "coloc/dem/dem.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <sstream>

#include "contact.hpp"
#include "generate.hpp"
#include "rng.hpp"

namespace coloc::dem {

using detail::Material;
using detail::Model;
using detail::PairCoeff;

namespace {
constexpr int kTagGhostCount = 4100, kTagGhost = 4200, kTagUpdate = 4300, kTagMigCount = 4400,
              kTagMig = 4500;
constexpr int kGhostBuild = 13;  // id, material, radius, mass, x3, v3, omega3
constexpr int kGhostUpdate = 9;  // x3, v3, omega3
constexpr int kMigFixed = 17;    // id, material, radius, mass, x3, v3, omega3, fExt3, nhist
const char* kAxis[3] = {"x", "y", "z"};

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(4);
  os << v;
  return os.str();
}

template <class T>
std::size_t cap(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

/// Grow-only capacity with 1/8 headroom (instead of the 2x of push_back): the arrays hold at
/// most ~12 % slack, and once the largest size has been seen nothing is allocated again.
/// Large buffers (>= 4 MiB) are marked for transparent huge pages (THP in "madvise" mode): the
/// first touch of a multi-million-particle set-up then takes one page fault per 2 MiB instead of
/// per 4 KiB (page faults were a third of a 2M-particle set-up), and the scattered partner reads
/// of the force loop miss the TLB less. Only the 2 MiB-aligned interior is marked; no effect on
/// the contents or the capacity.
template <class T>
void hugePages(std::vector<T>& v) {
  constexpr std::size_t kHuge = std::size_t{2} << 20;
  const std::size_t bytes = v.capacity() * sizeof(T);
  if (bytes < 2 * kHuge) return;
  const auto a = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t b = (a + kHuge - 1) & ~(kHuge - 1), e = (a + bytes) & ~(kHuge - 1);
  if (e > b) madvise(reinterpret_cast<void*>(b), e - b, MADV_HUGEPAGE);
}

template <class T>
void ensure(std::vector<T>& v, std::size_t need) {
  if (v.capacity() < need) {
    v.reserve(need + need / 8 + 16);
    hugePages(v);
  }
}

/// ensure() for a buffer filled row by row: when it must grow, it grows to the size extrapolated
/// from the rows done so far (+1/8), so a first build of millions of rows reallocates a few
/// times instead of ~100 times (1/8 steps).
template <class T>
void ensureRows(std::vector<T>& v, std::size_t need, std::size_t rowsDone, std::size_t rows) {
  if (v.capacity() >= need) return;
  const std::size_t est = rowsDone > 0 ? static_cast<std::size_t>(static_cast<double>(v.size()) /
                                                                  static_cast<double>(rowsDone) *
                                                                  static_cast<double>(rows))
                                       : 0;
  ensure(v, std::max(need, est));
}

/// After a row-by-row fill: an extrapolated capacity far above the size (more than 1/4) is
/// trimmed to the size + 1/8 (one copy; grow-only otherwise).
template <class T>
void trimRows(std::vector<T>& v) {
  const std::size_t n = v.size();
  if (v.capacity() > n + n / 4 + 64) {
    std::vector<T> t;
    t.reserve(n + n / 8 + 16);
    t.assign(v.begin(), v.end());
    v.swap(t);
    hugePages(v);
  }
}
}  // namespace

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
  std::array<std::array<bool, 2>, 3> wallOn{};
  // particles.boundary: the condition of each box face, for every rank (not only the boundary
  // blocks); Open = no wall (particles.walls false): a particle leaving is an error
  enum class Face { Wall, Outflow, Periodic, Open };
  std::array<std::array<Face, 2>, 3> face{};
  bool anyOutflow = false;
  // inflow (particles.inflow) and the flow tallies; every member of `flow` except the out ones
  // is global and identical on every rank (the out ones count this rank's removals)
  std::vector<detail::InflowInfo> inflow;
  DemFlow flow;
  std::int64_t inflowIdBase = 0;
  std::uint64_t seed = 0;
  std::vector<detail::NewParticle> incoming;  // accepted at the step's start, added at its rebuild
  bool forceRebuild = false;
  double skin = 0, rc = 0, overlapLimit = 0.2, dtFraction = 0.2;

  // bins
  Real3 origin{}, L{}, bs{}, lo{}, hi{};
  std::array<bool, 3> periodic{};
  std::array<long long, 3> NbG{}, binLo{}, binHi{};
  std::array<long long, 3> binSplit{1, 1, 1}, binMult{1, 1, 1};  // bin = cell/split or mult cells
  Int3 nb{}, nbx{};  // local bins, and with one ghost layer on each side
  std::vector<int> binOf, binStart, binItems;

  // Verlet list (full, owned rows)
  std::vector<int> rowStart, nbr;
  std::vector<int> slot;  // per entry: its history in the pool hS (-1: none)
  std::array<std::vector<double>, 3> x0;

  // Contact history pool: hS holds 3 doubles per slot. Between builds the slots are used by the
  // list entries of touching pairs (slot[]), with a free list; from the packing at a rebuild to
  // the next list build they are rows per owned particle (hStart, key hId), which migration
  // carries; the list build then takes its entries' slots from the rows (no second pool).
  std::vector<int> hStart;
  std::vector<std::int64_t> hId;
  std::vector<double> hS;
  std::vector<int> freeSlots;
  [[gnu::noinline, gnu::cold]] int newSlot() {
    std::size_t s;
    if (!freeSlots.empty()) {
      s = static_cast<std::size_t>(freeSlots.back());
      freeSlots.pop_back();
    } else {
      s = hId.size();
      ensure(hId, s + 1);
      hId.push_back(0);
      ensure(hS, 3 * s + 3);
      hS.resize(3 * s + 3);
    }
    hS[3 * s] = hS[3 * s + 1] = hS[3 * s + 2] = 0;
    return static_cast<int>(s);
  }
  [[gnu::noinline]] void freeSlot(int s) {
    ensure(freeSlots, freeSlots.size() + 1);
    freeSlots.push_back(s);
  }
  void compactPool();

  // ghost plan: send lists per axis and side (0: to the low neighbour, 1: to the high one)
  struct Swap {
    std::vector<int> send;
    double shift = 0;
    int recvStart = 0, recvCount = 0;  // ghosts received from the opposite neighbour
  };
  std::array<std::array<Swap, 2>, 3> swaps;
  std::array<std::vector<double>, 2> sbuf, rbuf;

  // scratch (grow-only)
  std::vector<int> perm, iscr, inScr;

  // diagnostics
  long long rebuilds = 0, steps = 0, contacts = 0, wallContacts = 0;
  double maxOverlap = 0;
  std::int64_t maxOverlapId = -1, maxOverlapPartner = 0;

  // setup
  void readMaterials(const Config& cfg);
  void setupBins(const Config& cfg, double dmax, long long total);
  void checkTimeStep();
  void setupFaces(const Config& cfg);
  bool beyondOutflow(std::size_t i, int* which) const;
  void removeOutflow();
  /// Owned row i kept as row w (w <= i) while rows before it leave (migration, outflow), its
  /// packed contact histories [h0, h1) moved down to hw on.
  void keepRow(std::size_t i, std::size_t w, int h0, int h1, int& hw);
  void insertInflow();
  double massOf(int material, double r) const {
    return mats[static_cast<std::size_t>(material)].density * 4.0 / 3.0 * M_PI * r * r * r;
  }
  void addParticle(const detail::NewParticle& q);
  long long gbinRaw(double x, int d) const {
    const double s = std::floor((x - origin[d]) / bs[d]);
    if (!(s > -1e15)) return -(1LL << 50);
    if (!(s < 1e15)) return 1LL << 50;
    return static_cast<long long>(s);
  }
  long long gbinClamped(double x, int d) const {
    return std::clamp(gbinRaw(x, d), 0LL, NbG[d] - 1);
  }
  bool owns(const double* x) const {
    for (int d = 0; d < 3; ++d) {
      const long long b = gbinClamped(x[d], d);
      if (b < binLo[d] || b >= binHi[d]) return false;
    }
    return true;
  }

  // steps
  void substep();
  void initialIntegrate();
  void finalIntegrate();
  bool decideRebuild();
  void rebuild(bool first);
  void packHistory();
  void migrate();
  void sortByBin();
  void buildGhosts();
  void updateGhosts();
  void buildLists();
  void computeForces(bool update);
  template <Model M, bool Rolling>
  void forces(bool update);
  bool rolling = false;  // any material pair with rolling resistance
  void exchange(int d, int tagBase, bool sizesKnown);
  void resizeAll(std::size_t n);
  std::size_t memory() const;
  void checkOverlap(double globalMax);
  // state (checkpoint/restart)
  int ownerRank(const double* x) const;
  void restore(DemState& st);
  DemState save();
  DemFlow globalFlow() const;  // collective: the out tallies summed over the ranks
  std::string where() const;
};

// ---------------------------------------------------------------------------------------------
// setup

DemSolver::Impl::Impl(const Decomposition& d, const Config& cfg, Timers& t, DemState* initial)
    : dec(d), comm(d.comm()), timers(t) {
  ScopedPhase setup(timers, Phase::Setup);
  const auto& grid = dec.grid();
  dt = cfg.number("particles.dt");
  model = cfg.string("particles.contact_model") == "linear" ? Model::Linear : Model::HertzMindlin;
  const auto grav = cfg.vec3("gravity");
  for (int k = 0; k < 3; ++k) g[k] = grav[k];
  overlapLimit = cfg.number("particles.overlap_limit");
  dtFraction = cfg.number("particles.dt_fraction");
  hStart.assign(1, 0);
  readMaterials(cfg);
  for (const auto& m : mats) rolling = rolling || m.rollingFriction > 0;

  const auto info = detail::inspectSources(cfg, grid, nMat);
  inflow = detail::inspectInflow(cfg, grid, nMat);
  seed = static_cast<std::uint64_t>(cfg.integer("particles.seed"));
  double rmax = 0;
  long long total = 0;
  for (const auto& s : info) {
    if (s.count > 0) rmax = std::max(rmax, s.rmax);
    total += s.count;
  }
  inflowIdBase = total;
  flow.due.assign(inflow.size(), 0);
  flow.inserted.assign(inflow.size(), 0);
  flow.dueMass.assign(inflow.size(), 0.0);
  flow.waiting.assign(inflow.size(), {});
  for (const auto& f : inflow) rmax = std::max(rmax, f.size.rmax());
  // bins must exist for the particles to come (setupBins checks them only when any will)
  const long long binTotal = total + (inflow.empty() ? 0 : 1);
  if (initial) {
    // a restart: the bins are those of the case (same sources: same bins as the run that wrote
    // the state), widened only if the state holds larger particles than the sources
    double rs = 0;
    for (const double r : initial->particles.radius) rs = std::max(rs, r);
    rmax = std::max(rmax, comm.max(rs));
    // (with inflow the bins stay those of the case: the run that wrote the state had them)
    if (total == 0 && inflow.empty())
      total = comm.sum(static_cast<long long>(initial->particles.nOwned));
  }
  if (total > 0 && nMat == 0)
    throw ConfigError("particles.materials", "at least one material is required");
  const double dmax = 2 * rmax;
  skin = cfg.number("particles.skin") * dmax;
  rc = dmax + skin;
  setupFaces(cfg);
  for (int k = 0; k < 3; ++k)
    wallOn[k] = {face[k][0] == Face::Wall && dec.atLowBoundary(k),
                 face[k][1] == Face::Wall && dec.atHighBoundary(k)};
  setupBins(cfg, dmax, std::max(total, binTotal));

  if (initial) {
    restore(*initial);
    checkTimeStep();
    return;
  }
  // Two passes over the sources: count this rank's particles, size every array once (exactly),
  // then fill them (growing ~23 arrays particle by particle cost a third of a 2M-particle set-up
  // in copies and page faults).
  {
    const auto ownsX = [this](const double* x) { return owns(x); };
    std::size_t count = 0;
    detail::generate(cfg, info, lo, hi, ownsX, [&count](const detail::NewParticle&) { ++count; });
    resizeAll(count);
    hStart.assign(count + 1, 0);
    detail::generate(cfg, info, lo, hi, ownsX,
                     [this](const detail::NewParticle& q) { addParticle(q); });
  }
  checkTimeStep();
  {
    double m = 0;
    for (std::size_t i = 0; i < p.nOwned; ++i) m += p.mass[i];
    double buf[2] = {static_cast<double>(p.nOwned), m};
    comm.sumInPlace(std::span<double>(buf, 2));
    flow.countInitial = static_cast<long long>(buf[0]);
    flow.massInitial = buf[1];
  }
  rebuild(true);
  {
    ScopedPhase f(timers, Phase::DemForce);
    computeForces(false);
  }
  checkOverlap(comm.max(maxOverlap));
}

void DemSolver::Impl::setupFaces(const Config& cfg) {
  const auto& grid = dec.grid();
  const bool wallsOn = cfg.boolean("particles.walls");
  const char* names[3][2] = {{"xlo", "xhi"}, {"ylo", "yhi"}, {"zlo", "zhi"}};
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) {
      const std::string key = std::string("particles.boundary.") + names[d][s];
      const std::string v = cfg.string(key);
      Face f;
      if (v == "auto") {
        f = grid.periodic[d] ? Face::Periodic : (wallsOn ? Face::Wall : Face::Open);
      } else if (v == "periodic") {
        if (!grid.periodic[d])
          throw ConfigError(key,
                            std::string("periodic needs a periodic fluid axis (domain.periodic.") +
                                kAxis[d] + " = true)");
        f = Face::Periodic;
      } else {
        if (grid.periodic[d])
          throw ConfigError(key, "'" + v + "' on a periodic axis (domain.periodic." + kAxis[d] +
                                     " = true): use periodic or auto");
        f = v == "wall" ? Face::Wall : Face::Outflow;
      }
      face[d][s] = f;
      anyOutflow = anyOutflow || f == Face::Outflow;
    }
  for (std::size_t n = 0; n < inflow.size(); ++n) {
    const auto& f = inflow[n];
    if (face[f.axis][f.side] == Face::Outflow)
      throw ConfigError("particles.inflow[" + std::to_string(n) + "].face",
                        std::string("the face ") + names[f.axis][f.side] +
                            " is an outflow face (particles.boundary): the particles would "
                            "leave as they enter");
    for (std::size_t m = 0; m < n; ++m) {
      const auto& g = inflow[m];
      if (g.axis == f.axis && g.side == f.side && f.pmin[0] < g.pmax[0] && g.pmin[0] < f.pmax[0] &&
          f.pmin[1] < g.pmax[1] && g.pmin[1] < f.pmax[1])
        throw ConfigError(
            "particles.inflow[" + std::to_string(n) + "].patch",
            "overlaps the patch of particles.inflow[" + std::to_string(m) + "] on the same face");
    }
  }
}

void DemSolver::Impl::readMaterials(const Config& cfg) {
  const auto& list = cfg.at("particles.materials");
  for (const auto& m : list) {
    Material mt;
    mt.density = m["density"].get<double>();
    mt.young = m["young"].get<double>();
    mt.poisson = m["poisson"].get<double>();
    mt.restitution = m["restitution"].get<double>();
    mt.friction = m["friction"].get<double>();
    mt.rollingFriction = m["rolling_friction"].get<double>();
    mats.push_back(mt);
  }
  nMat = static_cast<int>(mats.size());
  if (nMat == 0) return;
  const auto wm = cfg.integer("particles.wall_material");
  if (wm >= nMat)
    throw ConfigError("particles.wall_material",
                      "no such material (" + std::to_string(nMat) + " declared)");
  const double kn = cfg.number("particles.linear.kn");
  const double ktr = cfg.number("particles.linear.kt_ratio");
  pairC.resize(static_cast<std::size_t>(nMat * nMat));
  wallC.resize(static_cast<std::size_t>(nMat));
  for (int a = 0; a < nMat; ++a) {
    for (int b = 0; b < nMat; ++b)
      pairC[static_cast<std::size_t>(a * nMat + b)] = detail::mix(mats[a], mats[b], kn, ktr);
    wallC[static_cast<std::size_t>(a)] =
        detail::mix(mats[a], mats[static_cast<std::size_t>(wm)], kn, ktr);
  }
}

BinLayout binLayout(const Config& cfg, const GlobalGrid& grid,
                    const std::array<std::vector<int>, 3>& cuts, double dmax, double skin,
                    long long total) {
  const bool any = total > 0;
  const double rc = dmax + skin;
  BinLayout out;
  // Automatic split of large cells: bins near the interaction range, but never (much) more
  // bins than particles: a few spheres in big cells must not allocate split^3 bins per cell.
  const double perCell = static_cast<double>(total) / static_cast<double>(grid.cellCount());
  const long long splitCap =
      std::max(1LL, static_cast<long long>(std::floor(std::cbrt(std::max(1.0, 8.0 * perCell)))));
  const long long kc = cfg.integer("particles.bin_cells");
  const long long ks = cfg.integer("particles.bin_split");
  if (kc > 0 && ks > 0)
    throw ConfigError("particles.bin_split",
                      "give particles.bin_cells or particles.bin_split, "
                      "not both");
  const auto range = [&] {
    return "the interaction range " + fmt(rc) + " m (largest diameter " + fmt(dmax) + " m + skin " +
           fmt(skin) + " m)";
  };
  for (int d = 0; d < 3; ++d) {
    const double h = grid.spacing(d);
    const auto& cd = cuts[d];
    const auto divides = [&](long long k) {
      return std::all_of(cd.begin(), cd.end(), [k](int c) { return c % k == 0; });
    };
    long long multiple = 1, split = 1;
    std::string key;
    if (ks > 0) {
      split = ks;
      key = "particles.bin_split";
    } else if (kc > 0) {
      multiple = kc;
      key = "particles.bin_cells";
      if (!divides(kc))
        throw ConfigError(key, "a bin of " + std::to_string(kc) + " cells does not fit the " +
                                   "blocks along " + kAxis[d] + ": every block edge (cell " +
                                   "cuts of the decomposition) must fall on a bin edge");
    } else {
      key = "particles.bin_cells";
      if (h >= rc) {
        split = rc > 0 ? std::clamp(static_cast<long long>(std::floor(h / rc)), 1LL,
                                    std::min(64LL, splitCap))
                       : 1;
      } else {
        multiple = static_cast<long long>(std::ceil(rc / h));
        while (multiple <= grid.cells[d] && (!divides(multiple) || multiple * h < rc)) ++multiple;
        if (multiple > grid.cells[d])
          throw ConfigError(key, std::string("no bin made of whole cells holds ") + range() +
                                     " and fits the blocks along " + kAxis[d] + " (cell " + fmt(h) +
                                     " m): use larger cells or fewer ranks");
      }
    }
    out.size[d] = split > 1 ? h / static_cast<double>(split) : h * static_cast<double>(multiple);
    out.split[d] = split;
    out.multiple[d] = split > 1 ? 1 : multiple;
    if (any && out.size[d] < rc)
      throw ConfigError(key, "the bin edge " + fmt(out.size[d]) + " m along " + kAxis[d] +
                                 " is smaller than " + range());
    out.globalBins[d] = split > 1 ? grid.cells[d] * split : grid.cells[d] / multiple;
    if (any && grid.periodic[d] && out.globalBins[d] < 2)
      throw ConfigError(key, std::string("a periodic axis needs at least 2 bins (") + kAxis[d] +
                                 " has " + std::to_string(out.globalBins[d]) +
                                 "): the box must be at least "
                                 "twice " +
                                 range());
  }
  return out;
}

void DemSolver::Impl::setupBins(const Config& cfg, double dmax, long long total) {
  const auto& grid = dec.grid();
  const BinLayout b = binLayout(cfg, grid, dec.cuts(), dmax, skin, total);
  for (int d = 0; d < 3; ++d) {
    origin[d] = grid.origin[d];
    L[d] = grid.length[d];
    periodic[d] = grid.periodic[d];
    bs[d] = b.size[d];
    binSplit[d] = b.split[d];
    binMult[d] = b.multiple[d];
    NbG[d] = b.globalBins[d];
    binLo[d] = b.blockBinLo(d, dec.lo()[d]);
    binHi[d] = b.blockBinLo(d, dec.hi()[d]);
    nb[d] = static_cast<int>(binHi[d] - binLo[d]);
    nbx[d] = nb[d] + 2;
    lo[d] = b.lo(grid, d, binLo[d]);
    hi[d] = b.hi(grid, d, binHi[d]);
  }
}

CaseParticles caseParticles(const Config& cfg, const GlobalGrid& grid) {
  const int nMat = static_cast<int>(cfg.at("particles.materials").size());
  const auto info = detail::inspectSources(cfg, grid, nMat);
  double rmax = 0;
  long long total = 0;
  for (const auto& s : info) {
    if (s.count > 0) rmax = std::max(rmax, s.rmax);
    total += s.count;
  }
  CaseParticles out;
  const double dmax = 2 * rmax;
  out.skin = cfg.number("particles.skin") * dmax;
  out.dmax = dmax;
  out.range = dmax + out.skin;
  out.total = total;
  Real3 lo = grid.origin, hi{};
  for (int d = 0; d < 3; ++d) hi[d] = grid.origin[d] + grid.length[d];
  const auto all = [](const double*) { return true; };
  std::size_t count = 0;
  detail::generate(cfg, info, lo, hi, all, [&count](const detail::NewParticle&) { ++count; });
  for (auto& x : out.x) x.reserve(count);
  detail::generate(cfg, info, lo, hi, all, [&out](const detail::NewParticle& q) {
    for (int d = 0; d < 3; ++d) out.x[d].push_back(q.x[d]);
    out.rMin = out.x[0].size() == 1 ? q.radius : std::min(out.rMin, q.radius);
    out.rMax = std::max(out.rMax, q.radius);
  });
  return out;
}

void DemSolver::Impl::checkTimeStep() {
  // Rayleigh time (Hertz): pi r sqrt(rho/G) / (0.1631 nu + 0.8766), G = E/(2(1+nu))
  // (Li, Xu & Thornton 2005); linear: collision time pi sqrt(m*/k_n) with m* = m_min/2.
  // The particles to come (inflow) count with the smallest radius of their distribution.
  double tLim = std::numeric_limits<double>::infinity();
  const auto limit = [&](int mat, double r, double mass) {
    const auto& m = mats[static_cast<std::size_t>(mat)];
    double t;
    if (model == Model::HertzMindlin) {
      const double G = m.young / (2 * (1 + m.poisson));
      t = M_PI * r * std::sqrt(m.density / G) / (0.1631 * m.poisson + 0.8766);
    } else {
      t = M_PI * std::sqrt(0.5 * mass / pairC[0].kn);
    }
    tLim = std::min(tLim, t);
  };
  for (std::size_t i = 0; i < p.nOwned; ++i) limit(p.material[i], p.radius[i], p.mass[i]);
  for (const auto& f : inflow) {
    const double r = f.size.rmin();
    limit(f.material, r, massOf(f.material, r));
  }
  tLim = comm.min(tLim);
  if (!std::isfinite(tLim)) return;
  if (dt > dtFraction * tLim) {
    const char* what = model == Model::HertzMindlin ? "Rayleigh time" : "linear collision time";
    throw ConfigError("particles.dt", "time step " + fmt(dt) + " s is above " + fmt(dtFraction) +
                                          " of the " + what + " " + fmt(tLim) +
                                          " s of the smallest particle: use at most " +
                                          fmt(dtFraction * tLim) + " s");
  }
}

void DemSolver::Impl::addParticle(const detail::NewParticle& q) {
  const std::size_t n = p.nOwned + 1;
  if (p.id.size() < n) resizeAll(n);  // sized beforehand by the constructor's counting pass
  const std::size_t i = n - 1;
  p.nOwned = n;
  p.id[i] = q.id;
  p.material[i] = q.material;
  p.radius[i] = q.radius;
  p.mass[i] = massOf(q.material, q.radius);
  for (int d = 0; d < 3; ++d) {
    p.x[d][i] = q.x[d];
    p.v[d][i] = q.v[d];
    p.omega[d][i] = p.f[d][i] = p.torque[d][i] = p.fExt[d][i] = 0;
  }
  if (hStart.size() < n + 1) {
    ensure(hStart, n + 1);
    hStart.resize(n + 1);
  }
  hStart[n] = hStart[n - 1];
}

void DemSolver::Impl::resizeAll(std::size_t n) {
  ensure(p.id, n);
  ensure(p.material, n);
  ensure(p.radius, n);
  ensure(p.mass, n);
  for (int d = 0; d < 3; ++d) {
    ensure(p.x[d], n);
    ensure(p.v[d], n);
    ensure(p.omega[d], n);
    ensure(p.f[d], n);
    ensure(p.torque[d], n);
    ensure(p.fExt[d], n);
  }
  p.id.resize(n);
  p.material.resize(n);
  p.radius.resize(n);
  p.mass.resize(n);
  for (int d = 0; d < 3; ++d) {
    p.x[d].resize(n);
    p.v[d].resize(n);
    p.omega[d].resize(n);
    p.f[d].resize(n);
    p.torque[d].resize(n);
    p.fExt[d].resize(n);
  }
}

// ---------------------------------------------------------------------------------------------
// time step

void DemSolver::Impl::substep() {
  if (frozen) {
    ++steps;
    time = static_cast<double>(steps) * dt;  // no accumulated round-off
    return;
  }
  if (!inflow.empty()) {
    ScopedPhase t(timers, Phase::DemNeighbor);
    insertInflow();
  }
  {
    ScopedPhase t(timers, Phase::DemIntegrate);
    initialIntegrate();
  }
  bool again;
  {
    ScopedPhase t(timers, Phase::DemNeighbor);
    again = decideRebuild();
  }
  if (again) {
    rebuild(false);
  } else {
    ScopedPhase t(timers, Phase::DemGhost);
    updateGhosts();
  }
  {
    ScopedPhase t(timers, Phase::DemForce);
    computeForces(true);
  }
  {
    ScopedPhase t(timers, Phase::DemIntegrate);
    finalIntegrate();
  }
  ++steps;
  time = static_cast<double>(steps) * dt;
}

void DemSolver::Impl::initialIntegrate() {
  const std::size_t n = p.nOwned;
  const double h = 0.5 * dt;
  for (int d = 0; d < 3; ++d) {
    double* x = p.x[d].data();
    double* v = p.v[d].data();
    const double* f = p.f[d].data();
    const double* m = p.mass.data();
    for (std::size_t i = 0; i < n; ++i) {
      v[i] += h * f[i] / m[i];
      x[i] += dt * v[i];
    }
    double* w = p.omega[d].data();
    const double* t = p.torque[d].data();
    const double* r = p.radius.data();
    for (std::size_t i = 0; i < n; ++i) w[i] += h * t[i] / (0.4 * m[i] * r[i] * r[i]);
  }
}

void DemSolver::Impl::finalIntegrate() {
  const std::size_t n = p.nOwned;
  const double h = 0.5 * dt;
  for (int d = 0; d < 3; ++d) {
    double* v = p.v[d].data();
    const double* f = p.f[d].data();
    const double* m = p.mass.data();
    for (std::size_t i = 0; i < n; ++i) v[i] += h * f[i] / m[i];
    double* w = p.omega[d].data();
    const double* t = p.torque[d].data();
    const double* r = p.radius.data();
    for (std::size_t i = 0; i < n; ++i) w[i] += h * t[i] / (0.4 * m[i] * r[i] * r[i]);
  }
}

std::string DemSolver::Impl::where() const {
  return " on rank " + std::to_string(dec.rank()) + " at step " + std::to_string(steps) +
         ", t = " + fmt(time) + " s";
}

void DemSolver::Impl::checkOverlap(double globalMax) {
  if (globalMax <= overlapLimit) return;
  std::string msg;
  if (maxOverlap > overlapLimit) {
    msg = "particle " + std::to_string(maxOverlapId) + " overlaps " +
          (maxOverlapPartner < 0 ? std::string("a wall")
                                 : "particle " + std::to_string(maxOverlapPartner)) +
          " by " + fmt(maxOverlap) + " of the smaller radius" + where() +
          " (limit particles.overlap_limit = " + fmt(overlapLimit) +
          "): reduce particles.dt, the velocities, or stiffen the material";
  }
  comm.raiseIfAny(msg);
}

bool DemSolver::Impl::decideRebuild() {
  double m2 = 0;
  const std::size_t n = p.nOwned;
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = p.x[0][i] - x0[0][i], dy = p.x[1][i] - x0[1][i], dz = p.x[2][i] - x0[2][i];
    double d2 = dx * dx + dy * dy + dz * dz;
    if (!(d2 <= std::numeric_limits<double>::max())) d2 = std::numeric_limits<double>::max();
    m2 = std::max(m2, d2);
  }
  // a centre beyond an outflow face, or particles entering, rebuild now (removal, insertion)
  if (forceRebuild) m2 = std::numeric_limits<double>::max();
  forceRebuild = false;
  if (anyOutflow)
    for (std::size_t i = 0; i < n; ++i)
      if (beyondOutflow(i, nullptr)) {
        m2 = std::numeric_limits<double>::max();
        break;
      }
  double buf[2] = {m2, maxOverlap};
  comm.maxInPlace(std::span<double>(buf, 2));
  checkOverlap(buf[1]);
  return buf[0] > 0.25 * skin * skin;
}

// ---------------------------------------------------------------------------------------------
// outflow and inflow

bool DemSolver::Impl::beyondOutflow(std::size_t i, int* which) const {
  for (int d = 0; d < 3; ++d) {
    const double x = p.x[d][i];
    if (face[d][0] == Face::Outflow && x < origin[d]) {
      if (which) *which = 2 * d;
      return true;
    }
    if (face[d][1] == Face::Outflow && x > origin[d] + L[d]) {
      if (which) *which = 2 * d + 1;
      return true;
    }
  }
  return false;
}

void DemSolver::Impl::keepRow(std::size_t i, std::size_t w, int h0, int h1, int& hw) {
  if (w != i) {
    p.id[w] = p.id[i];
    p.material[w] = p.material[i];
    p.radius[w] = p.radius[i];
    p.mass[w] = p.mass[i];
    for (int k = 0; k < 3; ++k) {
      p.x[k][w] = p.x[k][i];
      p.v[k][w] = p.v[k][i];
      p.omega[k][w] = p.omega[k][i];
      p.f[k][w] = p.f[k][i];
      p.torque[k][w] = p.torque[k][i];
      p.fExt[k][w] = p.fExt[k][i];
    }
  }
  hStart[w] = hw;
  for (int e = h0; e < h1; ++e, ++hw) {
    hId[static_cast<std::size_t>(hw)] = hId[static_cast<std::size_t>(e)];
    for (int k = 0; k < 3; ++k)
      hS[3 * static_cast<std::size_t>(hw) + static_cast<std::size_t>(k)] =
          hS[3 * static_cast<std::size_t>(e) + static_cast<std::size_t>(k)];
  }
}

void DemSolver::Impl::removeOutflow() {
  // After packHistory (rows per owned particle): particles whose centre is beyond an outflow
  // face leave with their rows; rows of other particles keyed by their ids are taken by no list
  // entry at the next build and become free slots (the histories are dropped).
  const std::size_t n = p.nOwned;
  std::size_t w = 0;
  int hw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int h0 = hStart[i], h1 = hStart[i + 1];
    int fc = 0;
    if (beyondOutflow(i, &fc)) {
      ++flow.countOut;
      flow.massOut += p.mass[i];
      ++flow.countOutByFace[static_cast<std::size_t>(fc)];
      continue;
    }
    keepRow(i, w, h0, h1, hw);
    ++w;
  }
  if (w == n) return;
  p.nOwned = w;
  p.nGhost = 0;
  hStart.resize(w + 1);
  hStart[w] = hw;
  hId.resize(static_cast<std::size_t>(hw));
  hS.resize(3 * static_cast<std::size_t>(hw));
}

void DemSolver::Impl::insertInflow() {
  // At the start of a step (owned and ghost positions current): the particles due by now join
  // their source's waiting list (in id order); the first min(waiting, sites) of them are
  // candidates, candidate j on site P(j) of the patch (P a pseudo-random permutation drawn per
  // step, so candidates never overlap each other), at an offset drawn from its id and the step.
  // A candidate is checked by the rank owning its centre against the local particles (owned and
  // ghosts: every particle within a diameter of it is one); one allreduce of the verdicts, and
  // the accepted candidates enter while the others wait for the next step (another site).
  // Everything but the overlap test is computed alike on every rank.
  const double t = static_cast<double>(steps) * dt;
  const std::size_t nIn = inflow.size();
  std::size_t total = 0;
  for (std::size_t n = 0; n < nIn; ++n) {
    const auto& f = inflow[n];
    const double te = f.end > 0 ? std::min(t, f.end) : t;
    const long long before = flow.due[n];
    if (te > f.start) {
      if (f.rate > 0) {
        flow.due[n] =
            std::max(flow.due[n], static_cast<long long>(std::floor(f.rate * (te - f.start))));
      } else {
        while (flow.dueMass[n] < f.massRate * (te - f.start)) {
          const auto id = static_cast<std::uint64_t>(
              inflowIdBase + flow.due[n] * static_cast<long long>(nIn) + static_cast<long long>(n));
          flow.dueMass[n] += massOf(f.material, f.size.radius(detail::uniform01(seed, id, 1)));
          ++flow.due[n];
        }
      }
    }
    auto& w = flow.waiting[n];
    for (long long k = before; k < flow.due[n]; ++k) w.push_back(k);
    total += static_cast<std::size_t>(std::min(static_cast<long long>(w.size()), f.na * f.nb));
  }
  if (total == 0) return;
  const auto candidate = [&](std::size_t n, long long j, detail::NewParticle& q) {
    const auto& f = inflow[n];
    const detail::RandomPermutation perm(
        static_cast<std::uint64_t>(f.na * f.nb),
        detail::hash3(seed, 0x1f10 + n, static_cast<std::uint64_t>(steps)));
    const auto site = static_cast<long long>(perm(static_cast<std::uint64_t>(j)));
    q.id = inflowIdBase +
           flow.waiting[n][static_cast<std::size_t>(j)] * static_cast<long long>(nIn) +
           static_cast<long long>(n);
    const auto uid = static_cast<std::uint64_t>(q.id);
    q.material = f.material;
    q.radius = f.size.radius(detail::uniform01(seed, uid, 1));
    const long long ij[2] = {site % f.na, site / f.na};
    const int ab[2] = {f.a, f.b};
    const double free = std::max(0.0, 0.5 * f.s - q.radius);
    const auto stream = 1000 + 4 * static_cast<std::uint64_t>(steps);
    for (int k = 0; k < 2; ++k)
      q.x[ab[k]] =
          f.pmin[k] + (static_cast<double>(ij[k]) + 0.5) * f.s +
          free * (2.0 * detail::uniform01(seed, uid, stream + static_cast<std::uint64_t>(k)) - 1.0);
    q.x[f.axis] = f.side == 0 ? origin[f.axis] + 0.5 * f.s : origin[f.axis] + L[f.axis] - 0.5 * f.s;
    for (int d = 0; d < 3; ++d) {
      q.v[d] = f.v[static_cast<std::size_t>(d)];
      if (f.spread > 0)
        q.v[d] += f.spread *
                  (2.0 * detail::uniform01(seed, uid, 10 + static_cast<std::uint64_t>(d)) - 1.0);
    }
  };
  const auto overlaps = [&](const detail::NewParticle& q) {
    int b[3];
    for (int d = 0; d < 3; ++d)
      b[d] = static_cast<int>(std::clamp(gbinRaw(q.x[d], d) - binLo[d], 0LL,
                                         static_cast<long long>(nb[d] - 1))) +
             1;
    for (int z = b[2] - 1; z <= b[2] + 1; ++z)
      for (int y = b[1] - 1; y <= b[1] + 1; ++y)
        for (int x = b[0] - 1; x <= b[0] + 1; ++x) {
          const auto bin = static_cast<std::size_t>(x + nbx[0] * (y + nbx[1] * z));
          for (int e = binStart[bin]; e < binStart[bin + 1]; ++e) {
            const auto i = static_cast<std::size_t>(binItems[static_cast<std::size_t>(e)]);
            double r2 = 0;
            for (int d = 0; d < 3; ++d) r2 += (p.x[d][i] - q.x[d]) * (p.x[d][i] - q.x[d]);
            const double rs = p.radius[i] + q.radius;
            if (r2 < rs * rs) return true;
          }
        }
    return false;
  };
  // verdicts: 1 = rejected by the owner of the candidate's centre (max over the ranks)
  ensure(inScr, total);
  inScr.assign(total, 0);
  detail::NewParticle q;
  for (std::size_t n = 0, c = 0; n < nIn; ++n) {
    const long long m =
        std::min(static_cast<long long>(flow.waiting[n].size()), inflow[n].na * inflow[n].nb);
    for (long long j = 0; j < m; ++j, ++c) {
      candidate(n, j, q);
      if (owns(q.x) && overlaps(q)) inScr[c] = 1;
    }
  }
  comm.maxInPlace(std::span<int>(inScr.data(), total));
  for (std::size_t n = 0, c = 0; n < nIn; ++n) {
    auto& w = flow.waiting[n];
    const long long m = std::min(static_cast<long long>(w.size()), inflow[n].na * inflow[n].nb);
    std::size_t keep = 0;
    for (long long j = 0; j < m; ++j, ++c) {
      const auto ju = static_cast<std::size_t>(j);
      if (inScr[c] != 0) {
        w[keep++] = w[ju];
        continue;
      }
      candidate(n, j, q);
      flow.massIn += massOf(q.material, q.radius);
      ++flow.inserted[n];
      ++flow.countIn;
      forceRebuild = true;
      if (owns(q.x)) {
        ensure(incoming, incoming.size() + 1);
        incoming.push_back(q);
      }
    }
    // the rejected candidates keep their order, ahead of the ones that were not candidates
    for (std::size_t j = static_cast<std::size_t>(m); j < w.size(); ++j) w[keep++] = w[j];
    w.resize(keep);
  }
}

std::vector<double> DemFlow::pack() const {
  std::vector<double> v = {static_cast<double>(countInitial), massInitial,
                           static_cast<double>(countIn),      massIn,
                           static_cast<double>(countOut),     massOut};
  for (long long c : countOutByFace) v.push_back(static_cast<double>(c));
  v.push_back(static_cast<double>(due.size()));
  for (std::size_t n = 0; n < due.size(); ++n) {
    v.push_back(static_cast<double>(due[n]));
    v.push_back(static_cast<double>(inserted[n]));
    v.push_back(dueMass[n]);
    const auto& w = n < waiting.size() ? waiting[n] : std::vector<long long>{};
    v.push_back(static_cast<double>(w.size()));
    for (long long k : w) v.push_back(static_cast<double>(k));
  }
  return v;
}

DemFlow DemFlow::unpack(const std::vector<double>& v) {
  DemFlow f;
  if (v.size() < 13) return f;
  f.countInitial = static_cast<long long>(v[0]);
  f.massInitial = v[1];
  f.countIn = static_cast<long long>(v[2]);
  f.massIn = v[3];
  f.countOut = static_cast<long long>(v[4]);
  f.massOut = v[5];
  for (std::size_t k = 0; k < 6; ++k) f.countOutByFace[k] = static_cast<long long>(v[6 + k]);
  const auto m = static_cast<std::size_t>(v[12]);
  std::size_t q = 13;
  for (std::size_t n = 0; n < m && q + 4 <= v.size(); ++n) {
    f.due.push_back(static_cast<long long>(v[q]));
    f.inserted.push_back(static_cast<long long>(v[q + 1]));
    f.dueMass.push_back(v[q + 2]);
    const auto nw = static_cast<std::size_t>(v[q + 3]);
    q += 4;
    std::vector<long long> w;
    for (std::size_t k = 0; k < nw && q < v.size(); ++k, ++q)
      w.push_back(static_cast<long long>(v[q]));
    f.waiting.push_back(std::move(w));
  }
  return f;
}

// ---------------------------------------------------------------------------------------------
// rebuild: history, migration, sort, ghosts, lists

void DemSolver::Impl::rebuild(bool first) {
  {
    ScopedPhase t(timers, Phase::DemMigrate);
    if (!first) packHistory();
    if (anyOutflow) removeOutflow();
    if (!incoming.empty()) {
      p.nGhost = 0;
      for (const auto& q : incoming) addParticle(q);
      incoming.clear();
    }
    migrate();
  }
  {
    ScopedPhase t(timers, Phase::DemNeighbor);
    sortByBin();
  }
  {
    ScopedPhase t(timers, Phase::DemGhost);
    buildGhosts();
  }
  {
    ScopedPhase t(timers, Phase::DemNeighbor);
    buildLists();
  }
  if (!first) ++rebuilds;
}

void DemSolver::Impl::packHistory() {
  // The history pool becomes rows per owned particle (the format migration carries and the list
  // build reads), keyed by the partner's global id (walls: -1..-6), shear as seen from the row's
  // particle. An owned-ghost pair has one row, under its owned particle; an owned-owned pair one
  // under its holder, and a second one under the partner when the two are bound for different
  // ranks or only one of them wraps across a periodic face (the pair is then computed by each
  // side for its own particle, with its own copy, as every owned-ghost pair). Done in place: the
  // live pool slots are permuted into row order (no second pool).
  const std::size_t n = p.nOwned, nAll = p.size();
  ensure(iscr, n);
  iscr.resize(n);
  for (std::size_t i = 0; i < n; ++i) {  // destination rank and periodic wrap of every particle
    double x[3];
    int wrap = 0;
    for (int d = 0, w = 1; d < 3; ++d, w *= 3) {
      x[d] = p.x[d][i];
      if (periodic[d]) {
        if (x[d] < origin[d]) {
          x[d] += L[d];
          wrap += w;
        } else if (x[d] >= origin[d] + L[d]) {
          x[d] -= L[d];
          wrap += 2 * w;
        }
      }
    }
    iscr[i] = (comm.size() > 1 ? ownerRank(x) * 27 : 0) + wrap;
  }
  const auto dup = [&](std::size_t a, int j) {
    return a < n && j >= 0 && static_cast<std::size_t>(j) < n &&
           iscr[a] != iscr[static_cast<std::size_t>(j)];
  };
  // pass 1: rows per particle; slots of zero histories are dropped
  ensure(hStart, n + 1);
  hStart.assign(n + 1, 0);
  for (std::size_t q = 0; q < nAll; ++q) {
    const auto a = static_cast<std::size_t>(binItems[q]);
    for (int e = rowStart[q]; e < rowStart[q + 1]; ++e) {
      const int s = slot[static_cast<std::size_t>(e)];
      if (s < 0) continue;
      const double* v = &hS[3 * static_cast<std::size_t>(s)];
      if (v[0] == 0 && v[1] == 0 && v[2] == 0) {
        slot[static_cast<std::size_t>(e)] = -1;
        continue;
      }
      const int j = nbr[static_cast<std::size_t>(e)];
      ++hStart[(a < n ? a : static_cast<std::size_t>(j)) + 1];
      if (dup(a, j)) ++hStart[static_cast<std::size_t>(j) + 1];
    }
  }
  for (std::size_t i = 0; i < n; ++i) hStart[i + 1] += hStart[i];
  const auto T = static_cast<std::size_t>(hStart[n]);
  const std::size_t M = std::max(T, hId.size());
  ensure(hId, M);
  hId.resize(M);
  ensure(hS, 3 * M);
  hS.resize(3 * M);
  // target position of every pool slot (live ones to their row, the others to the free rows),
  // kept in hId, which pass 2 overwrites with the keys: bits 0-31 the target, bit 32 "position
  // taken", bit 33 "moved"
  constexpr std::int64_t kNone = 0xffffffffLL, kTakenPos = 1LL << 32, kMoved = 1LL << 33;
  for (std::size_t s = 0; s < M; ++s) hId[s] = kNone;
  const auto setTarget = [&](std::size_t s, std::size_t pos) {
    hId[s] = (hId[s] & ~kNone) | static_cast<std::int64_t>(pos);
    hId[pos] |= kTakenPos;
  };
  std::vector<int>& cur = binOf;  // free until the re-sort
  ensure(cur, n);
  cur.assign(hStart.begin(), hStart.end() - 1);
  for (std::size_t q = 0; q < nAll; ++q) {
    const auto a = static_cast<std::size_t>(binItems[q]);
    for (int e = rowStart[q]; e < rowStart[q + 1]; ++e) {
      const int s = slot[static_cast<std::size_t>(e)];
      if (s < 0) continue;
      const int j = nbr[static_cast<std::size_t>(e)];
      const int pos = cur[a < n ? a : static_cast<std::size_t>(j)]++;
      if (dup(a, j)) ++cur[static_cast<std::size_t>(j)];
      setTarget(static_cast<std::size_t>(s), static_cast<std::size_t>(pos));
    }
  }
  for (std::size_t s = 0, pos = 0; s < M; ++s) {
    if ((hId[s] & kNone) != kNone) continue;
    while (hId[pos] & kTakenPos) ++pos;
    setTarget(s, pos);
  }
  for (std::size_t s = 0; s < M; ++s) {  // move slot s to its target, cycle by cycle
    if (hId[s] & kMoved) continue;
    double v[3] = {hS[3 * s], hS[3 * s + 1], hS[3 * s + 2]};
    std::size_t k = s;
    for (;;) {
      const auto t = static_cast<std::size_t>(hId[k] & kNone);
      hId[k] |= kMoved;
      for (int c = 0; c < 3; ++c) std::swap(v[c], hS[3 * t + static_cast<std::size_t>(c)]);
      if (t == s) break;
      k = t;
    }
  }
  // pass 2: keys, orientation, second copies
  cur.assign(hStart.begin(), hStart.end() - 1);
  for (std::size_t q = 0; q < nAll; ++q) {
    const auto a = static_cast<std::size_t>(binItems[q]);
    for (int e = rowStart[q]; e < rowStart[q + 1]; ++e) {
      if (slot[static_cast<std::size_t>(e)] < 0) continue;
      const int j = nbr[static_cast<std::size_t>(e)];
      double* v = &hS[3 * static_cast<std::size_t>(cur[a < n ? a : static_cast<std::size_t>(j)])];
      if (a < n) {
        hId[static_cast<std::size_t>(cur[a]++)] = j >= 0 ? p.id[static_cast<std::size_t>(j)] : j;
      } else {  // under the owned partner, seen from it
        hId[static_cast<std::size_t>(cur[static_cast<std::size_t>(j)]++)] = p.id[a];
        for (int c = 0; c < 3; ++c) v[c] = -v[c];
      }
      if (dup(a, j)) {
        const auto r = static_cast<std::size_t>(cur[static_cast<std::size_t>(j)]++);
        hId[r] = p.id[a];
        for (int c = 0; c < 3; ++c) hS[3 * r + static_cast<std::size_t>(c)] = -v[c];
      }
    }
  }
  hId.resize(T);
  hS.resize(3 * T);
  freeSlots.clear();
}

void DemSolver::Impl::exchange(int d, int tagBase, bool sizesKnown) {
  const int nLo = dec.neighbor(d, -1), nHi = dec.neighbor(d, +1);
  const double t0 = comm.wtime();
  if (!sizesKnown) {
    rbuf[0].resize(static_cast<std::size_t>(
        comm.exchangeCount(static_cast<int>(sbuf[0].size()), nLo, nHi, tagBase)));
    rbuf[1].resize(static_cast<std::size_t>(
        comm.exchangeCount(static_cast<int>(sbuf[1].size()), nHi, nLo, tagBase + 1)));
  }
  MPI_Request req[4];
  req[0] = comm.irecv(std::span<double>(rbuf[0]), nHi, tagBase + 2);
  req[1] = comm.irecv(std::span<double>(rbuf[1]), nLo, tagBase + 3);
  req[2] = comm.isend(std::span<const double>(sbuf[0]), nLo, tagBase + 2);
  req[3] = comm.isend(std::span<const double>(sbuf[1]), nHi, tagBase + 3);
  Comm::waitAll(std::span<MPI_Request>(req, 4));
  long long bytes = 0, msgs = 0;
  const int me = dec.rank();
  for (int s = 0; s < 2; ++s) {
    const int to = s == 0 ? nLo : nHi;
    if (to == MPI_PROC_NULL || to == me) continue;
    bytes += static_cast<long long>(sbuf[static_cast<std::size_t>(s)].size() * sizeof(double));
    msgs += sizesKnown ? 1 : 2;
  }
  if (msgs > 0)
    timers.book(Exchange::IntraPhysics, bytes, msgs, comm.wtime() - t0,
                tagBase >= kTagMigCount && tagBase < kTagMigCount + 30 ? Traffic::DemMigrate
                                                                        : Traffic::DemGhost);
}

void DemSolver::Impl::migrate() {
  std::string err;
  p.nGhost = 0;
  resizeAll(p.nOwned);
  for (int d = 0; d < 3; ++d) {
    sbuf[0].clear();
    sbuf[1].clear();
    const std::size_t n = p.nOwned;
    std::size_t w = 0;
    int hw = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double& x = p.x[d][i];
      int dir = 0;
      if (!std::isfinite(x) || !std::isfinite(p.v[d][i]) || !std::isfinite(p.omega[d][i])) {
        if (err.empty())
          err = "particle " + std::to_string(p.id[i]) + " has a non-finite " +
                (!std::isfinite(x)           ? "position"
                 : !std::isfinite(p.v[d][i]) ? "velocity"
                                             : "angular velocity") +
                where() + ": the run blew up (time step too large, or a NaN in the forces)";
        dir = 0;
      } else if (periodic[d]) {
        const double top = origin[d] + L[d];
        if (x < origin[d]) {
          x += L[d];
          if (x >= top) x = origin[d];
          dir = -1;
        } else if (x >= top) {
          x -= L[d];
          if (x < origin[d]) x = origin[d];
          dir = +1;
        } else {
          const long long b = gbinClamped(x, d);
          dir = b < binLo[d] ? -1 : (b >= binHi[d] ? +1 : 0);
        }
      } else if (x < origin[d] || x > origin[d] + L[d]) {
        if (err.empty())
          err = "particle " + std::to_string(p.id[i]) + " left the box through the " +
                (x < origin[d] ? "low " : "high ") + kAxis[d] + " face" + where() +
                " (x = " + fmt(p.x[0][i]) + ", " + fmt(p.x[1][i]) + ", " + fmt(p.x[2][i]) +
                "): too fast for the walls, or walls are off";
      } else {
        const long long b = gbinClamped(x, d);
        dir = b < binLo[d] ? -1 : (b >= binHi[d] ? +1 : 0);
      }
      const int h0 = hStart[i], h1 = hStart[i + 1];
      if (dir != 0 && dec.neighbor(d, dir) == MPI_PROC_NULL) dir = 0;  // cannot happen
      if (dir == 0) {
        keepRow(i, w, h0, h1, hw);
        ++w;
      } else {
        auto& b = sbuf[dir > 0 ? 1 : 0];
        b.push_back(static_cast<double>(p.id[i]));
        b.push_back(p.material[i]);
        b.push_back(p.radius[i]);
        b.push_back(p.mass[i]);
        for (int k = 0; k < 3; ++k) b.push_back(p.x[k][i]);
        for (int k = 0; k < 3; ++k) b.push_back(p.v[k][i]);
        for (int k = 0; k < 3; ++k) b.push_back(p.omega[k][i]);
        for (int k = 0; k < 3; ++k) b.push_back(p.fExt[k][i]);
        b.push_back(h1 - h0);
        for (int e = h0; e < h1; ++e) {
          b.push_back(static_cast<double>(hId[static_cast<std::size_t>(e)]));
          for (int k = 0; k < 3; ++k)
            b.push_back(hS[3 * static_cast<std::size_t>(e) + static_cast<std::size_t>(k)]);
        }
      }
    }
    p.nOwned = w;
    hStart.resize(w + 1);
    hStart[w] = hw;
    hId.resize(static_cast<std::size_t>(hw));
    hS.resize(3 * static_cast<std::size_t>(hw));
    if (dec.neighbor(d, -1) == MPI_PROC_NULL && dec.neighbor(d, +1) == MPI_PROC_NULL) continue;
    exchange(d, kTagMigCount + 10 * d, false);
    for (int s = 0; s < 2; ++s) {
      const auto& b = rbuf[static_cast<std::size_t>(s)];
      std::size_t q = 0;
      while (q < b.size()) {
        const std::size_t i = p.nOwned;
        resizeAll(i + 1);
        p.nOwned = i + 1;
        p.id[i] = static_cast<std::int64_t>(b[q]);
        p.material[i] = static_cast<int>(b[q + 1]);
        p.radius[i] = b[q + 2];
        p.mass[i] = b[q + 3];
        for (int k = 0; k < 3; ++k) {
          p.x[k][i] = b[q + 4 + k];
          p.v[k][i] = b[q + 7 + k];
          p.omega[k][i] = b[q + 10 + k];
          p.fExt[k][i] = b[q + 13 + k];
          p.f[k][i] = p.torque[k][i] = 0;
        }
        const int nh = static_cast<int>(b[q + 16]);
        q += kMigFixed;
        ensure(hId, hId.size() + static_cast<std::size_t>(nh));
        ensure(hS, hS.size() + 3 * static_cast<std::size_t>(nh));
        ensure(hStart, hStart.size() + 1);
        for (int e = 0; e < nh; ++e, q += 4) {
          hId.push_back(static_cast<std::int64_t>(b[q]));
          hS.insert(hS.end(), b.data() + q + 1, b.data() + q + 4);
        }
        hStart.push_back(static_cast<int>(hId.size()));
      }
    }
  }
  comm.raiseIfAny(err);
}

void DemSolver::Impl::sortByBin() {
  const std::size_t n = p.nOwned;
  const std::size_t nBins = static_cast<std::size_t>(nbx[0]) * nbx[1] * nbx[2];
  ensure(binOf, n);
  binOf.resize(n);
  binStart.assign(nBins + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    int b[3];
    for (int d = 0; d < 3; ++d)
      b[d] = static_cast<int>(std::clamp(gbinRaw(p.x[d][i], d) - binLo[d], 0LL,
                                         static_cast<long long>(nb[d] - 1))) +
             1;
    const int lb = b[0] + nbx[0] * (b[1] + nbx[1] * b[2]);
    binOf[i] = lb;
    ++binStart[static_cast<std::size_t>(lb) + 1];
  }
  for (std::size_t b = 0; b < nBins; ++b) binStart[b + 1] += binStart[b];
  ensure(perm, n);
  perm.resize(n);
  iscr.assign(binStart.begin(), binStart.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    perm[static_cast<std::size_t>(iscr[static_cast<std::size_t>(binOf[i])]++)] =
        static_cast<int>(i);
  for (std::size_t b = 0; b < nBins; ++b) {
    const int a = binStart[b], e = binStart[b + 1];
    if (e - a > 1)
      std::sort(perm.begin() + a, perm.begin() + e, [this](int u, int v) {
        return p.id[static_cast<std::size_t>(u)] < p.id[static_cast<std::size_t>(v)];
      });
  }
  // applied in place, cycle by cycle (no scratch array: 16 bytes per particle less); a visited
  // position is marked by complementing its perm entry, restored after each array
  const auto apply = [&](auto& vec) {
    for (std::size_t s = 0; s < n; ++s) {
      if (perm[s] < 0) continue;
      auto tmp = vec[s];
      std::size_t k = s;
      for (;;) {
        const auto src = static_cast<std::size_t>(perm[k]);
        perm[k] = ~perm[k];
        if (src == s) {
          vec[k] = tmp;
          break;
        }
        vec[k] = vec[src];
        k = src;
      }
    }
    for (std::size_t k = 0; k < n; ++k) perm[k] = ~perm[k];
  };
  apply(p.id);
  apply(p.material);
  apply(p.radius);
  apply(p.mass);
  for (int d = 0; d < 3; ++d) {
    apply(p.x[d]);
    apply(p.v[d]);
    apply(p.omega[d]);
    apply(p.f[d]);
    apply(p.torque[d]);
    apply(p.fExt[d]);
  }
  // the history rows stay in pre-sort order: buildLists reads row perm[k] for particle k
  for (int d = 0; d < 3; ++d) ensure(x0[d], n);
  for (int d = 0; d < 3; ++d)
    x0[d].assign(p.x[d].begin(), p.x[d].begin() + static_cast<std::ptrdiff_t>(n));
}

void DemSolver::Impl::buildGhosts() {
  const Int3 coords = dec.coords(), dims = dec.dims();
  for (int d = 0; d < 3; ++d) {
    const std::size_t nBefore = p.size();
    for (int s = 0; s < 2; ++s) {
      auto& sw = swaps[d][static_cast<std::size_t>(s)];
      auto& b = sbuf[static_cast<std::size_t>(s)];
      sw.send.clear();
      b.clear();
      sw.shift = 0;
      if (dec.neighbor(d, s == 0 ? -1 : 1) == MPI_PROC_NULL) continue;
      if (periodic[d]) {
        if (s == 0 && coords[d] == 0) sw.shift = L[d];
        if (s == 1 && coords[d] == dims[d] - 1) sw.shift = -L[d];
      }
      const double* x = p.x[d].data();
      const double lim = s == 0 ? lo[d] + rc : hi[d] - rc;
      for (std::size_t i = 0; i < nBefore; ++i) {
        if (s == 0 ? x[i] < lim : x[i] >= lim) {
          sw.send.push_back(static_cast<int>(i));
          b.push_back(static_cast<double>(p.id[i]));
          b.push_back(p.material[i]);
          b.push_back(p.radius[i]);
          b.push_back(p.mass[i]);
          for (int k = 0; k < 3; ++k) b.push_back(p.x[k][i] + (k == d ? sw.shift : 0.0));
          for (int k = 0; k < 3; ++k) b.push_back(p.v[k][i]);
          for (int k = 0; k < 3; ++k) b.push_back(p.omega[k][i]);
        }
      }
    }
    if (dec.neighbor(d, -1) == MPI_PROC_NULL && dec.neighbor(d, +1) == MPI_PROC_NULL) {
      for (int s = 0; s < 2; ++s) swaps[d][static_cast<std::size_t>(s)].recvCount = 0;
      continue;
    }
    exchange(d, kTagGhostCount + 10 * d, false);
    for (int s = 0; s < 2; ++s) {
      const auto& b = rbuf[static_cast<std::size_t>(s)];
      const std::size_t cnt = b.size() / kGhostBuild;
      const std::size_t start = p.size();
      auto& sw = swaps[d][static_cast<std::size_t>(s)];
      sw.recvStart = static_cast<int>(start);
      sw.recvCount = static_cast<int>(cnt);
      resizeAll(start + cnt);
      p.nGhost += cnt;
      for (std::size_t q = 0; q < cnt; ++q) {
        const double* r = &b[q * kGhostBuild];
        const std::size_t i = start + q;
        p.id[i] = static_cast<std::int64_t>(r[0]);
        p.material[i] = static_cast<int>(r[1]);
        p.radius[i] = r[2];
        p.mass[i] = r[3];
        for (int k = 0; k < 3; ++k) {
          p.x[k][i] = r[4 + k];
          p.v[k][i] = r[7 + k];
          p.omega[k][i] = r[10 + k];
          p.f[k][i] = p.torque[k][i] = p.fExt[k][i] = 0;
        }
      }
    }
  }
}

void DemSolver::Impl::updateGhosts() {
  for (int d = 0; d < 3; ++d) {
    if (dec.neighbor(d, -1) == MPI_PROC_NULL && dec.neighbor(d, +1) == MPI_PROC_NULL) continue;
    for (int s = 0; s < 2; ++s) {
      const auto& sw = swaps[d][static_cast<std::size_t>(s)];
      auto& b = sbuf[static_cast<std::size_t>(s)];
      b.resize(sw.send.size() * kGhostUpdate);
      double* o = b.data();
      for (const int i : sw.send) {
        const auto u = static_cast<std::size_t>(i);
        for (int k = 0; k < 3; ++k) o[k] = p.x[k][u] + (k == d ? sw.shift : 0.0);
        for (int k = 0; k < 3; ++k) o[3 + k] = p.v[k][u];
        for (int k = 0; k < 3; ++k) o[6 + k] = p.omega[k][u];
        o += kGhostUpdate;
      }
      rbuf[static_cast<std::size_t>(s)].resize(static_cast<std::size_t>(sw.recvCount) *
                                               kGhostUpdate);
    }
    exchange(d, kTagUpdate + 10 * d, true);
    for (int s = 0; s < 2; ++s) {
      const auto& sw = swaps[d][static_cast<std::size_t>(s)];
      const double* r = rbuf[static_cast<std::size_t>(s)].data();
      for (int q = 0; q < sw.recvCount; ++q, r += kGhostUpdate) {
        const auto i = static_cast<std::size_t>(sw.recvStart + q);
        for (int k = 0; k < 3; ++k) {
          p.x[k][i] = r[k];
          p.v[k][i] = r[3 + k];
          p.omega[k][i] = r[6 + k];
        }
      }
    }
  }
}

void DemSolver::Impl::buildLists() {
  const std::size_t nAll = p.size(), n = p.nOwned;
  const std::size_t nBins = static_cast<std::size_t>(nbx[0]) * nbx[1] * nbx[2];
  // bins of every local particle (owned clamped into the block, ghosts into the ghost layer)
  ensure(binOf, nAll);
  binOf.resize(nAll);
  binStart.assign(nBins + 1, 0);
  for (std::size_t i = 0; i < nAll; ++i) {
    const bool own = i < n;
    int b[3];
    for (int d = 0; d < 3; ++d) {
      const long long lb = gbinRaw(p.x[d][i], d) - binLo[d];
      b[d] = static_cast<int>(own ? std::clamp(lb, 0LL, static_cast<long long>(nb[d] - 1))
                                  : std::clamp(lb, -1LL, static_cast<long long>(nb[d]))) +
             1;
    }
    binOf[i] = b[0] + nbx[0] * (b[1] + nbx[1] * b[2]);
    ++binStart[static_cast<std::size_t>(binOf[i]) + 1];
  }
  for (std::size_t b = 0; b < nBins; ++b) binStart[b + 1] += binStart[b];
  ensure(binItems, nAll);
  binItems.resize(nAll);
  iscr.assign(binStart.begin(), binStart.end() - 1);
  for (std::size_t i = 0; i < nAll; ++i)
    binItems[static_cast<std::size_t>(iscr[static_cast<std::size_t>(binOf[i])]++)] =
        static_cast<int>(i);
  for (std::size_t b = 0; b < nBins; ++b) {
    const int a = binStart[b], e = binStart[b + 1];
    if (e - a > 1 && binItems[static_cast<std::size_t>(e - 1)] >= static_cast<int>(n))
      std::sort(binItems.begin() + a, binItems.begin() + e, [this](int u, int v) {
        return p.id[static_cast<std::size_t>(u)] < p.id[static_cast<std::size_t>(v)];
      });
  }
  // Half list. binItems is every local particle in (bin, id) order: the canonical key K (the
  // bin's (z, y, x) position, unwrapped across periodic faces, then the global id) orders the
  // holders the same way at any rank count. The row of holder a lists the partners b with
  // K_b > K_a: the rest of a's bin, then the 13 forward stencil bins in increasing index, each
  // in increasing id; at least one of a, b is owned (ghost holders list owned partners only).
  // Walls close the rows of owned particles.
  ensure(rowStart, nAll + 1);
  rowStart.resize(nAll + 1);
  nbr.clear();
  slot.clear();
  const int sy = nbx[0], sz = nbx[0] * nbx[1];
  int fwd[13][3], nf = 0;
  for (int dz = 0; dz <= 1; ++dz)
    for (int dy = dz == 0 ? 0 : -1; dy <= 1; ++dy)
      for (int dx = (dz == 0 && dy == 0) ? 1 : -1; dx <= 1; ++dx) {
        fwd[nf][0] = dx;
        fwd[nf][1] = dy;
        fwd[nf][2] = dz;
        ++nf;
      }
  const double* X = p.x[0].data();
  const double* Y = p.x[1].data();
  const double* Z = p.x[2].data();
  const double* R = p.radius.data();
  // the history of (a, b) as seen from a: the row of a keyed by b's id (or the wall code), else
  // the row of b keyed by a's id, negated in place; the entry takes that row as its pool slot
  // (rows are in pre-sort order: row perm[i] for particle i; a taken row's key is cleared)
  constexpr std::int64_t kTaken = std::numeric_limits<std::int64_t>::min();
  const auto lookup = [&](std::size_t a, int b) {
    if (a < n) {
      const auto h = static_cast<std::size_t>(perm[a]);
      const std::int64_t key = b >= 0 ? p.id[static_cast<std::size_t>(b)] : b;
      for (int e = hStart[h]; e < hStart[h + 1]; ++e)
        if (hId[static_cast<std::size_t>(e)] == key) {
          hId[static_cast<std::size_t>(e)] = kTaken;
          slot.push_back(e);
          return;
        }
    }
    if (b >= 0 && static_cast<std::size_t>(b) < n) {
      const auto h = static_cast<std::size_t>(perm[static_cast<std::size_t>(b)]);
      for (int e = hStart[h]; e < hStart[h + 1]; ++e)
        if (hId[static_cast<std::size_t>(e)] == p.id[a]) {
          hId[static_cast<std::size_t>(e)] = kTaken;
          for (int k = 0; k < 3; ++k) hS[3 * static_cast<std::size_t>(e) + k] *= -1.0;
          slot.push_back(e);
          return;
        }
    }
    slot.push_back(-1);
  };
  for (std::size_t q = 0; q < nAll; ++q) {
    rowStart[q] = static_cast<int>(nbr.size());
    ensureRows(nbr, nbr.size() + 64, q, nAll);
    ensureRows(slot, slot.size() + 64, q, nAll);
    const auto a = static_cast<std::size_t>(binItems[q]);
    const bool ownA = a < n;
    const int ba = binOf[a];
    const int bx = ba % nbx[0], by = (ba / nbx[0]) % nbx[1], bz = ba / sz;
    const auto visit = [&](int from, int to) {
      for (int t = from; t < to; ++t) {
        const int j = binItems[static_cast<std::size_t>(t)];
        const auto u = static_cast<std::size_t>(j);
        if (!ownA && u >= n) continue;
        const double ex = X[a] - X[u], ey = Y[a] - Y[u], ez = Z[a] - Z[u];
        const double cut = R[a] + R[u] + skin;
        if (ex * ex + ey * ey + ez * ez < cut * cut) {
          nbr.push_back(j);
          lookup(a, j);
        }
      }
    };
    visit(static_cast<int>(q) + 1, binStart[static_cast<std::size_t>(ba) + 1]);
    for (int f = 0; f < nf; ++f) {
      const int cx = bx + fwd[f][0], cy = by + fwd[f][1], cz = bz + fwd[f][2];
      if (cx < 0 || cx >= nbx[0] || cy < 0 || cy >= nbx[1] || cz >= nbx[2]) continue;
      const auto b = static_cast<std::size_t>(cx + cy * sy + cz * sz);
      visit(binStart[b], binStart[b + 1]);
    }
    if (!ownA) continue;
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        if (!wallOn[d][static_cast<std::size_t>(s)]) continue;
        const double dist = s == 0 ? p.x[d][a] - origin[d] : origin[d] + L[d] - p.x[d][a];
        if (dist < R[a] + skin) {
          const int code = -1 - (2 * d + s);
          nbr.push_back(code);
          lookup(a, code);
        }
      }
  }
  rowStart[nAll] = static_cast<int>(nbr.size());
  trimRows(nbr);
  trimRows(slot);
  // rows no entry took are free slots
  freeSlots.clear();
  for (std::size_t e = 0; e < hId.size(); ++e)
    if (hId[e] != kTaken) freeSlot(static_cast<int>(e));
}

// ---------------------------------------------------------------------------------------------
// forces

void DemSolver::Impl::computeForces(bool update) {
  if (model == Model::HertzMindlin)
    rolling ? forces<Model::HertzMindlin, true>(update)
            : forces<Model::HertzMindlin, false>(update);
  else
    rolling ? forces<Model::Linear, true>(update) : forces<Model::Linear, false>(update);
}

// Each pair is computed once (Newton's third law inside the rank; an owned-ghost pair is
// computed by each rank for its own particle, "newton off" across ranks, so nothing goes back to
// a ghost's owner). Holders are visited in K order (see buildLists), so a particle receives the
// terms of its lower-K partners (pushed by their rows, in increasing K), then those of its own
// row (increasing K), then its walls: the same sum in the same order at any rank count, and the
// pair term itself is computed from the same operands (lower K first) everywhere.
template <Model M, bool Rolling>
void DemSolver::Impl::forces(bool update) {
  const std::size_t n = p.nOwned, nAll = p.size();
  double* FX[3] = {p.f[0].data(), p.f[1].data(), p.f[2].data()};
  double* TX[3] = {p.torque[0].data(), p.torque[1].data(), p.torque[2].data()};
  for (int k = 0; k < 3; ++k) {
    const double* fe = p.fExt[k].data();
    const double* ms = p.mass.data();
    for (std::size_t i = 0; i < n; ++i) {
      FX[k][i] = ms[i] * g[k] + fe[i];
      TX[k][i] = 0;
    }
  }
  const double* X[3] = {p.x[0].data(), p.x[1].data(), p.x[2].data()};
  const double* V[3] = {p.v[0].data(), p.v[1].data(), p.v[2].data()};
  const double* W[3] = {p.omega[0].data(), p.omega[1].data(), p.omega[2].data()};
  const double* R = p.radius.data();
  const double* Ms = p.mass.data();
  const int* mat = p.material.data();
  const int* nb = nbr.data();
  int* sl = slot.data();
  long long nc = 0, nw = 0;
  double worst = 0;
  std::int64_t worstId = -1, worstPartner = 0;
  for (std::size_t q = 0; q < nAll; ++q) {
    const int e0 = rowStart[q], e1 = rowStart[q + 1];
    if (e0 == e1) continue;
    const auto i = static_cast<std::size_t>(binItems[q]);
    const bool ownI = i < n;
    const double ri = R[i], mi = Ms[i];
    double F[3] = {0, 0, 0}, T[3] = {0, 0, 0};
    if (ownI)
      for (int k = 0; k < 3; ++k) {
        F[k] = FX[k][i];
        T[k] = TX[k][i];
      }
    const double xi[3] = {X[0][i], X[1][i], X[2][i]};
    const double vi[3] = {V[0][i], V[1][i], V[2][i]};
    const double wi[3] = {W[0][i], W[1][i], W[2][i]};
    const PairCoeff* rowC = &pairC[static_cast<std::size_t>(mat[i] * nMat)];
    for (int e = e0; e < e1; ++e) {
      const int j = nb[e];
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        const double dx[3] = {xi[0] - X[0][u], xi[1] - X[1][u], xi[2] - X[2][u]};
        const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
        const double rj = R[u], rs = ri + rj;
        if (r2 >= rs * rs) {
          if (sl[e] >= 0) freeSlot(sl[e]), sl[e] = -1;
          continue;
        }
        if (sl[e] < 0) sl[e] = newSlot();
        double* sh = &hS[3 * static_cast<std::size_t>(sl[e])];
        // R* and m* with one division, independent of the distance (in parallel with the
        // square root and 1/r on the critical path)
        const double mj = Ms[u], msum = mi + mj;
        const double q0 = 1.0 / (rs * msum);
        const double Reff = ri * rj * (msum * q0);
        const double meff = mi * mj * (rs * q0);
        const double r = std::sqrt(r2);
        const double inv = 1.0 / r;
        const double nrm[3] = {dx[0] * inv, dx[1] * inv, dx[2] * inv};
        const double delta = rs - r;
        const double vr[3] = {vi[0] - V[0][u], vi[1] - V[1][u], vi[2] - V[2][u]};
        const double ws[3] = {ri * wi[0] + rj * W[0][u], ri * wi[1] + rj * W[1][u],
                              ri * wi[2] + rj * W[2][u]};
        const double wr[3] = {wi[0] - W[0][u], wi[1] - W[1][u], wi[2] - W[2][u]};
        double Fp[3], c[3], rl[3];
        detail::pairForce<M, Rolling>(rowC[mat[u]], dt, update, nrm, delta, Reff, meff, vr, ws, wr,
                                      sh, Fp, c, rl);
        if (ownI) {
          for (int k = 0; k < 3; ++k) {
            F[k] += Fp[k];
            T[k] -= ri * c[k];
            if constexpr (Rolling) T[k] -= rl[k];
          }
          ++nc;
        }
        if (u < n) {
          for (int k = 0; k < 3; ++k) {
            FX[k][u] -= Fp[k];
            TX[k][u] -= rj * c[k];
            if constexpr (Rolling) TX[k][u] += rl[k];
          }
          ++nc;
        }
        const double rmin = std::min(ri, rj);
        if (delta > worst * rmin) {  // largest overlap / smaller radius, divided only when larger
          worst = delta / rmin;
          worstId = p.id[ownI ? i : u];
          worstPartner = p.id[ownI ? u : i];
        }
      } else {
        const int w = -1 - j, d = w / 2, s = w % 2;
        const double dist = s == 0 ? xi[d] - origin[d] : origin[d] + L[d] - xi[d];
        const double delta = ri - dist;
        if (delta <= 0) {
          if (sl[e] >= 0) freeSlot(sl[e]), sl[e] = -1;
          continue;
        }
        if (sl[e] < 0) sl[e] = newSlot();
        double* sh = &hS[3 * static_cast<std::size_t>(sl[e])];
        double nrm[3] = {0, 0, 0};
        nrm[d] = s == 0 ? 1.0 : -1.0;
        const double ws[3] = {ri * wi[0], ri * wi[1], ri * wi[2]};
        detail::contactForce<M>(wallC[static_cast<std::size_t>(mat[i])], dt, update, nrm, delta, ri,
                                mi, ri, vi, ws, wi, sh, F, T);
        ++nw;
        const double ov = delta / ri;
        if (ov > worst) worst = ov, worstId = p.id[i], worstPartner = -1;
      }
    }
    if (ownI)
      for (int k = 0; k < 3; ++k) {
        FX[k][i] = F[k];
        TX[k][i] = T[k];
      }
  }
  contacts = nc;
  wallContacts = nw;
  maxOverlap = worst;
  maxOverlapId = worstId;
  maxOverlapPartner = worstPartner;
}

std::size_t DemSolver::Impl::memory() const {
  std::size_t b = cap(p.id) + cap(p.material) + cap(p.radius) + cap(p.mass);
  for (int d = 0; d < 3; ++d)
    b += cap(p.x[d]) + cap(p.v[d]) + cap(p.omega[d]) + cap(p.f[d]) + cap(p.torque[d]) +
         cap(p.fExt[d]) + cap(x0[d]);
  b += cap(binOf) + cap(binStart) + cap(binItems) + cap(rowStart) + cap(nbr) + cap(slot);
  b += cap(hStart) + cap(hId) + cap(hS) + cap(freeSlots);
  for (const auto& a : swaps)
    for (const auto& s : a) b += cap(s.send);
  b += cap(sbuf[0]) + cap(sbuf[1]) + cap(rbuf[0]) + cap(rbuf[1]);
  b += cap(perm) + cap(iscr);
  return b;
}

// ---------------------------------------------------------------------------------------------
// state: checkpoint/restart and re-balancing

int DemSolver::Impl::ownerRank(const double* x) const {
  Int3 cell{};
  for (int d = 0; d < 3; ++d) {
    const long long b = gbinClamped(x[d], d);
    cell[d] = static_cast<int>(binSplit[d] > 1 ? b / binSplit[d] : b * binMult[d]);
  }
  return dec.ownerOfCell(cell);
}

namespace {
/// Sends blocks[r] to rank r (all-to-all); returns what arrived, rank after rank.
std::vector<double> sendBlocks(const Comm& comm, const std::vector<std::vector<double>>& blocks) {
  const int P = comm.size();
  std::vector<int> sc(static_cast<std::size_t>(P)), rc, sd, rd;
  std::vector<double> send;
  for (int r = 0; r < P; ++r) {
    const auto& b = blocks[static_cast<std::size_t>(r)];
    sc[static_cast<std::size_t>(r)] = static_cast<int>(b.size());
    send.insert(send.end(), b.begin(), b.end());
  }
  comm.alltoall(sc, rc);
  Comm::displacements(sc, sd);
  std::vector<double> recv(static_cast<std::size_t>(Comm::displacements(rc, rd)));
  comm.alltoallv(std::span<const double>(send), sc, sd, std::span<double>(recv), rc, rd);
  return recv;
}
constexpr int kStateRec = 22;  // id, material, radius, mass, x3, v3, omega3, f3, torque3, fExt3
constexpr int kHistRec = 5;    // holder, partner, shear3
}  // namespace

DemFlow DemSolver::Impl::globalFlow() const {
  DemFlow f = flow;
  double buf[8] = {static_cast<double>(f.countOut), f.massOut};
  for (std::size_t k = 0; k < 6; ++k) buf[2 + k] = static_cast<double>(f.countOutByFace[k]);
  comm.sumInPlace(std::span<double>(buf, 8));
  f.countOut = static_cast<long long>(buf[0]);
  f.massOut = buf[1];
  for (std::size_t k = 0; k < 6; ++k) f.countOutByFace[k] = static_cast<long long>(buf[2 + k]);
  return f;
}

void DemSolver::Impl::restore(DemState& st) {
  const int P = comm.size();
  const auto& q = st.particles;
  time = st.time;
  steps = st.steps;
  rebuilds = st.rebuilds;
  {
    // the tallies are global (the same in every rank's state, or absent there): taken from
    // the lowest rank with the longest record; the out tallies continue on rank 0 only (they
    // are summed over the ranks)
    std::vector<double> v = st.flow.pack();
    const auto sizes = comm.allgather(static_cast<long long>(v.size()));
    int from = 0;
    for (int r = 1; r < P; ++r)
      if (sizes[static_cast<std::size_t>(r)] > sizes[static_cast<std::size_t>(from)]) from = r;
    v.resize(static_cast<std::size_t>(sizes[static_cast<std::size_t>(from)]));
    comm.broadcast(std::span<double>(v), from);
    const std::size_t nIn = inflow.size();
    flow = DemFlow::unpack(v);
    flow.due.resize(nIn, 0);
    flow.inserted.resize(nIn, 0);
    flow.dueMass.resize(nIn, 0.0);
    flow.waiting.resize(nIn);
    if (!comm.isRoot()) {
      flow.countOut = 0;
      flow.massOut = 0;
      flow.countOutByFace = {};
    }
  }
  // 1. particles to their owners (by position), a general all-to-all: any rank may hold any
  //    subset of the state
  std::vector<std::vector<double>> out(static_cast<std::size_t>(P));
  for (std::size_t i = 0; i < q.nOwned; ++i) {
    const double xi[3] = {q.x[0][i], q.x[1][i], q.x[2][i]};
    auto& b = out[static_cast<std::size_t>(ownerRank(xi))];
    b.push_back(static_cast<double>(q.id[i]));
    b.push_back(q.material[i]);
    b.push_back(q.radius[i]);
    b.push_back(q.mass[i]);
    for (const auto* a : {&q.x, &q.v, &q.omega, &q.f, &q.torque, &q.fExt})
      for (int k = 0; k < 3; ++k) b.push_back((*a)[k][i]);
  }
  std::vector<double> in = sendBlocks(comm, out);
  const std::size_t n = in.size() / kStateRec;
  resizeAll(n);
  p.nOwned = n;
  p.nGhost = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double* r = &in[i * kStateRec];
    p.id[i] = static_cast<std::int64_t>(r[0]);
    p.material[i] = static_cast<int>(r[1]);
    p.radius[i] = r[2];
    p.mass[i] = r[3];
    for (int k = 0; k < 3; ++k) {
      p.x[k][i] = r[4 + k];
      p.v[k][i] = r[7 + k];
      p.omega[k][i] = r[10 + k];
      p.f[k][i] = r[13 + k];
      p.torque[k][i] = r[16 + k];
      p.fExt[k][i] = r[19 + k];
    }
  }
  std::string err;
  for (std::size_t i = 0; i < n && err.empty(); ++i)
    if (p.material[i] < 0 || p.material[i] >= nMat)
      err = "restored particle " + std::to_string(p.id[i]) + " has material " +
            std::to_string(p.material[i]) + " (" + std::to_string(nMat) + " declared)";
  comm.raiseIfAny(err);
  // 2. histories to their holders through a directory (rank holder % P): the directory learns
  //    every holder's owner, then forwards; a history may sit on any rank, apart from its holder
  for (auto& b : out) b.clear();
  for (const auto& c : st.contacts) {
    if (c.holder < 0) {
      if (err.empty()) err = "a restored contact history has holder id " + std::to_string(c.holder);
      continue;
    }
    auto& b = out[static_cast<std::size_t>(c.holder % P)];
    b.push_back(static_cast<double>(c.holder));
    b.push_back(static_cast<double>(c.partner));
    b.insert(b.end(), c.shear.begin(), c.shear.end());
  }
  comm.raiseIfAny(err);
  st = DemState{};  // the input is no longer needed
  const std::vector<double> hist = sendBlocks(comm, out);
  for (auto& b : out) b.clear();
  for (std::size_t i = 0; i < n; ++i)
    out[static_cast<std::size_t>(p.id[i] % P)].push_back(static_cast<double>(p.id[i]));
  std::vector<double> reg = sendBlocks(comm, out);  // ids owned by each rank, rank after rank
  {
    std::vector<int> rc(static_cast<std::size_t>(P)), rd;
    std::vector<int> sc(static_cast<std::size_t>(P));
    for (int r = 0; r < P; ++r)
      sc[static_cast<std::size_t>(r)] = static_cast<int>(out[static_cast<std::size_t>(r)].size());
    comm.alltoall(sc, rc);
    std::vector<std::pair<std::int64_t, int>> owner;  // (id, owner rank)
    std::size_t k = 0;
    for (int r = 0; r < P; ++r)
      for (int c = 0; c < rc[static_cast<std::size_t>(r)]; ++c, ++k)
        owner.emplace_back(static_cast<std::int64_t>(reg[k]), r);
    std::sort(owner.begin(), owner.end());
    for (auto& b : out) b.clear();
    for (std::size_t h = 0; h + kHistRec <= hist.size(); h += kHistRec) {
      const auto id = static_cast<std::int64_t>(hist[h]);
      const auto it = std::lower_bound(owner.begin(), owner.end(), std::make_pair(id, -1));
      if (it == owner.end() || it->first != id) {
        if (err.empty())
          err = "a restored contact history names holder " + std::to_string(id) +
                ", which is not among the restored particles";
        continue;
      }
      auto& b = out[static_cast<std::size_t>(it->second)];
      b.insert(b.end(), hist.begin() + static_cast<std::ptrdiff_t>(h),
               hist.begin() + static_cast<std::ptrdiff_t>(h + kHistRec));
    }
  }
  comm.raiseIfAny(err);
  const std::vector<double> mine = sendBlocks(comm, out);
  // 3. history rows per local particle (the format migration and the list build use)
  std::vector<std::pair<std::int64_t, int>> byId(n);
  for (std::size_t i = 0; i < n; ++i) byId[i] = {p.id[i], static_cast<int>(i)};
  std::sort(byId.begin(), byId.end());
  const std::size_t nh = mine.size() / kHistRec;
  std::vector<int> row(nh);
  hStart.assign(n + 1, 0);
  for (std::size_t h = 0; h < nh; ++h) {
    const auto id = static_cast<std::int64_t>(mine[h * kHistRec]);
    const auto it = std::lower_bound(byId.begin(), byId.end(), std::make_pair(id, -1));
    row[h] = it->second;
    ++hStart[static_cast<std::size_t>(row[h]) + 1];
  }
  for (std::size_t i = 0; i < n; ++i) hStart[i + 1] += hStart[i];
  hId.assign(nh, 0);
  hS.assign(3 * nh, 0.0);
  iscr.assign(hStart.begin(), hStart.end() - 1);
  for (std::size_t h = 0; h < nh; ++h) {
    const auto e = static_cast<std::size_t>(iscr[static_cast<std::size_t>(row[h])]++);
    hId[e] = static_cast<std::int64_t>(mine[h * kHistRec + 1]);
    for (int k = 0; k < 3; ++k)
      hS[3 * e + static_cast<std::size_t>(k)] = mine[h * kHistRec + 2 + k];
  }
  // 4. the canonical rebuild (same orders as the one inside saveState), no force recomputation:
  //    the saved forces start the next velocity-Verlet half step; the force pass below only
  //    refreshes the diagnostics (contacts, overlap) and leaves f, torque and histories as saved
  checkTimeStep();
  rebuild(true);
  compactPool();  // the rows held every history twice (under both particles of a pair)
  {
    ScopedPhase f(timers, Phase::DemForce);
    std::vector<double> keep;
    keep.reserve(6 * n);
    for (const auto* a : {&p.f, &p.torque})
      for (int k = 0; k < 3; ++k) keep.insert(keep.end(), (*a)[k].begin(), (*a)[k].begin() + n);
    computeForces(false);
    std::size_t o = 0;
    for (auto* a : {&p.f, &p.torque})
      for (int k = 0; k < 3; ++k, o += n)
        std::copy(keep.begin() + static_cast<std::ptrdiff_t>(o),
                  keep.begin() + static_cast<std::ptrdiff_t>(o + n), (*a)[k].begin());
  }
  checkOverlap(comm.max(maxOverlap));
}

void DemSolver::Impl::compactPool() {
  std::vector<double> v;
  v.reserve(3 * (hId.size() - freeSlots.size()) + 16);
  for (auto& s : slot)
    if (s >= 0) {
      v.insert(v.end(), hS.begin() + 3 * s, hS.begin() + 3 * s + 3);
      s = static_cast<int>(v.size() / 3 - 1);
    }
  hS.swap(v);
  std::vector<std::int64_t>(hS.size() / 3, 0).swap(hId);
  std::vector<int>().swap(freeSlots);
}

DemState DemSolver::Impl::save() {
  rebuild(false);  // canonical: migration, (bin, id) order, lists; the restored run does the same
  DemState st;
  st.time = time;
  st.steps = steps;
  st.rebuilds = rebuilds;
  st.flow = globalFlow();
  const std::size_t n = p.nOwned;
  auto& q = st.particles;
  q.nOwned = n;
  q.nGhost = 0;
  q.id.assign(p.id.begin(), p.id.begin() + static_cast<std::ptrdiff_t>(n));
  q.material.assign(p.material.begin(), p.material.begin() + static_cast<std::ptrdiff_t>(n));
  q.radius.assign(p.radius.begin(), p.radius.begin() + static_cast<std::ptrdiff_t>(n));
  q.mass.assign(p.mass.begin(), p.mass.begin() + static_cast<std::ptrdiff_t>(n));
  for (int k = 0; k < 3; ++k) {
    const auto cp = [n](const std::vector<double>& a, std::vector<double>& b) {
      b.assign(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(n));
    };
    cp(p.x[k], q.x[k]);
    cp(p.v[k], q.v[k]);
    cp(p.omega[k], q.omega[k]);
    cp(p.f[k], q.f[k]);
    cp(p.torque[k], q.torque[k]);
    cp(p.fExt[k], q.fExt[k]);
  }
  // every touching history under each owned particle of the pair (a restart on other ranks may
  // separate them), as seen from that particle
  for (std::size_t q = 0; q < p.size(); ++q) {
    const auto a = static_cast<std::size_t>(binItems[q]);
    for (int e = rowStart[q]; e < rowStart[q + 1]; ++e) {
      const int sl = slot[static_cast<std::size_t>(e)];
      if (sl < 0) continue;
      const double* sh = &hS[3 * static_cast<std::size_t>(sl)];
      if (sh[0] == 0 && sh[1] == 0 && sh[2] == 0) continue;
      const int j = nbr[static_cast<std::size_t>(e)];
      if (a < n) {
        ContactHistory c;
        c.holder = p.id[a];
        c.partner = j >= 0 ? p.id[static_cast<std::size_t>(j)] : j;
        c.shear = {sh[0], sh[1], sh[2]};
        st.contacts.push_back(c);
      }
      if (j >= 0 && static_cast<std::size_t>(j) < n) {
        ContactHistory c;
        c.holder = p.id[static_cast<std::size_t>(j)];
        c.partner = p.id[a];
        c.shear = {-sh[0], -sh[1], -sh[2]};
        st.contacts.push_back(c);
      }
    }
  }
  return st;
}

// ---------------------------------------------------------------------------------------------
// public interface

DemSolver::DemSolver(const Decomposition& dec, const Config& cfg, Timers& timers)
    : impl_(std::make_unique<Impl>(dec, cfg, timers)) {}
DemSolver::DemSolver(const Decomposition& dec, const Config& cfg, Timers& timers, DemState initial)
    : impl_(std::make_unique<Impl>(dec, cfg, timers, &initial)) {}
DemState DemSolver::saveState() {
  return impl_->save();
}
DemSolver::~DemSolver() = default;
ParticleStore& DemSolver::particles() {
  return impl_->p;
}
const ParticleStore& DemSolver::particles() const {
  return impl_->p;
}
void DemSolver::substep() {
  impl_->substep();
}
double DemSolver::dt() const {
  return impl_->dt;
}
double DemSolver::time() const {
  return impl_->time;
}
void DemSolver::setFrozen(bool frozen) {
  impl_->frozen = frozen;
}
long long DemSolver::globalCount() const {
  return impl_->comm.sum(static_cast<long long>(impl_->p.nOwned));
}
void DemSolver::rebuildNow() {
  impl_->rebuild(false);
}
void DemSolver::computeForcesNow() {
  ScopedPhase t(impl_->timers, Phase::DemForce);
  impl_->computeForces(false);
}
double DemSolver::interactionRange() const {
  return impl_->rc;
}
double DemSolver::skin() const {
  return impl_->skin;
}
std::array<double, 3> DemSolver::binSize() const {
  return impl_->bs;
}
long long DemSolver::rebuildCount() const {
  return impl_->rebuilds;
}
std::size_t DemSolver::memoryBytes() const {
  return impl_->memory();
}
long long DemSolver::localContacts() const {
  return impl_->contacts;
}
long long DemSolver::localWallContacts() const {
  return impl_->wallContacts;
}

double DemSolver::contactEnergy() const {
  const auto& m = *impl_;
  const auto& p = m.p;
  const std::size_t n = p.nOwned;
  double e = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const auto i = static_cast<std::size_t>(m.binItems[q]);
    for (int k = m.rowStart[q]; k < m.rowStart[q + 1]; ++k) {
      const int j = m.nbr[static_cast<std::size_t>(k)];
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        double r2 = 0;
        for (int d = 0; d < 3; ++d) r2 += (p.x[d][i] - p.x[d][u]) * (p.x[d][i] - p.x[d][u]);
        const double rs = p.radius[i] + p.radius[u];
        if (r2 >= rs * rs) continue;
        // half of the pair's energy to each owned particle of the pair
        const double share = 0.5 * ((i < n ? 1 : 0) + (u < n ? 1 : 0));
        const auto& c = m.pairC[static_cast<std::size_t>(p.material[i] * m.nMat + p.material[u])];
        e += share *
             detail::normalEnergy(m.model, c, rs - std::sqrt(r2), p.radius[i] * p.radius[u] / rs);
      } else {
        const int w = -1 - j, d = w / 2, s = w % 2;
        const double dist = s == 0 ? p.x[d][i] - m.origin[d] : m.origin[d] + m.L[d] - p.x[d][i];
        const double delta = p.radius[i] - dist;
        if (delta > 0)
          e += detail::normalEnergy(m.model, m.wallC[static_cast<std::size_t>(p.material[i])],
                                    delta, p.radius[i]);
      }
    }
  }
  return m.comm.sum(e);
}

Json DemSolver::diagnostics() const {
  const auto& m = *impl_;
  double loc[6] = {static_cast<double>(m.p.nOwned),     static_cast<double>(m.contacts),
                   static_cast<double>(m.wallContacts), static_cast<double>(m.p.nGhost),
                   static_cast<double>(m.nbr.size()),   static_cast<double>(m.memory())};
  m.comm.sumInPlace(std::span<double>(loc, 6));
  const double n = std::max(1.0, loc[0]);
  Json j;
  j["count"] = static_cast<long long>(loc[0]);
  j["contacts_per_particle"] = loc[1] / n;
  j["wall_contacts"] = static_cast<long long>(loc[2]);
  j["ghosts"] = static_cast<long long>(loc[3]);
  j["neighbors_per_particle"] = loc[4] / n;
  j["rebuilds"] = m.rebuilds;
  j["bytes_per_particle"] = loc[5] / n;
  j["interaction_range"] = m.rc;
  j["skin"] = m.skin;
  j["bin_size"] = {m.bs[0], m.bs[1], m.bs[2]};
  j["dt"] = m.dt;
  j["frozen"] = m.frozen;
  // flow: mass in (initial + inflow) = mass out (outflow faces) + mass held
  const DemFlow f = m.globalFlow();
  double held = 0;
  for (std::size_t i = 0; i < m.p.nOwned; ++i) held += m.p.mass[i];
  held = m.comm.sum(held);
  j["count_initial"] = f.countInitial;
  j["count_in"] = f.countIn;
  j["count_out"] = f.countOut;
  j["mass_initial"] = f.massInitial;
  j["mass_in"] = f.massIn;
  j["mass_out"] = f.massOut;
  j["mass_held"] = held;
  const char* names[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};
  Json byFace = Json::object();
  for (std::size_t k = 0; k < 6; ++k)
    if (m.face[k / 2][k % 2] == Impl::Face::Outflow) byFace[names[k]] = f.countOutByFace[k];
  j["count_out_by_face"] = byFace;
  long long waiting = 0;
  for (const auto& w : f.waiting) waiting += static_cast<long long>(w.size());
  j["inflow_waiting"] = waiting;
  const double scale = f.massInitial + f.massIn;
  j["mass_balance"] = scale > 0 ? std::abs(scale - f.massOut - held) / scale : 0.0;
  return j;
}

}  // namespace coloc::dem
