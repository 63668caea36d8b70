// dem/src/dem.cpp — the linked-cell soft-sphere DEM on the shared decomposition.
//
// One sub-step (velocity Verlet, as LAMMPS/LIGGGHTS run it):
//   1. v += dt/2 F/m, x += dt v, omega += dt/2 T/I                     (DemIntegrate)
//   2. one allreduce: largest displacement since the last rebuild and largest overlap
//      -> rebuild when any particle moved more than skin/2            (DemNeighbour)
//   3. rebuild: contact history packed per particle, migration in three sweeps x, y, z
//      (DemMigrate); owned particles re-sorted by (bin, id) (DemNeighbour); ghosts within the
//      interaction range of every block face in three sweeps x, y, z, so edges and corners are
//      covered, periodic faces shift positions by the box length (DemGhost); bins and Verlet
//      lists (DemNeighbour).  Otherwise: ghost positions/velocities refreshed along the same
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

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "impl.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// time step

// One sub-step, phase by phase (as LAMMPS's verlet.cpp sequences its parts).
void DemSolver::Impl::substep() {
  if (frozen) return frozenSubstep();
  if (!inflow.empty()) timed(Phase::DemNeighbour, [&] { insertInflow(); });
  const double v2 =
      timed(Phase::DemIntegrate, [&] { return integrator.initialIntegrate(p, forces); });
  timers.syncPoint(comm);
  if (timed(Phase::DemNeighbour, [&] { return decideRebuild(v2); }))
    rebuild(false);
  else
    timed(Phase::DemGhost, [&] { exchange->updateGhosts(); });
  timed(Phase::DemForce, [&] { computeForces(true, true); });
  timed(Phase::DemIntegrate, [&] {
    integrator.finalIntegrate(p);
    if (heat.on) heat.integrate(p, integrator.dt);
  });
  advanceClock();
}

// A frozen sub-step (run.mode dummy_dem): nothing moves, no force is computed. With
// particles.heat the temperatures still evolve as in a sub-step of particles at rest: the ghosts'
// temperatures refreshed, conduction through the contacts of the frozen positions (the neighbour
// lists built at set-up stay valid: nothing moves), T integrated with the held heat_ext. With heat
// off it only advances the clock, as before.
void DemSolver::Impl::frozenSubstep() {
  if (heat.on) {
    timed(Phase::DemGhost, [&] { exchange->updateGhosts(); });
    timed(Phase::DemForce, [&] { heat.conduct(p, search); });
    timed(Phase::DemIntegrate, [&] { heat.integrate(p, integrator.dt); });
  }
  advanceClock();
}

void DemSolver::Impl::advanceClock() {
  ++steps;
  time = static_cast<double>(steps) * integrator.dt;  // no accumulated round-off
}

std::string DemSolver::Impl::where() const {
  return fmt::format(" on rank {} at step {}, t = {:.4g} s", dec.rank(), steps, time);
}

void DemSolver::Impl::checkOverlap(double globalMax) {
  if (globalMax <= overlapLimit) return;
  std::string msg;
  const ContactTally& t = forces.tally();
  if (t.maxOverlap > overlapLimit) {
    msg = fmt::format(
        "particle {} overlaps {} by {:.4g} of the smaller radius{} (limit "
        "particles.overlap_limit = {:.4g}): reduce particles.dt, the velocities, or stiffen the "
        "material",
        t.maxOverlapId,
        t.maxOverlapPartner < 0 ? std::string("a wall")
                                : fmt::format("particle {}", t.maxOverlapPartner),
        t.maxOverlap, where(), overlapLimit);
  }
  comm.raiseIfAny(msg);
}

bool DemSolver::Impl::decideRebuild(double v2) {
  double m2 = search.maxDisplacement2(p);
  const std::size_t n = p.nOwned;
  // a centre beyond an outflow face, or particles entering, rebuild now (removal, insertion)
  if (forceRebuild) m2 = std::numeric_limits<double>::max();
  forceRebuild = false;
  if (anyOutflow)
    for (std::size_t i = 0; i < n; ++i)
      if (beyondOutflow(i, nullptr)) {
        m2 = std::numeric_limits<double>::max();
        break;
      }
  // the same reduction carries the largest drift velocity: the inner list's displacement bound
  double buf[3] = {m2, forces.tally().maxOverlap, v2};
  comm.maxInPlace(std::span<double>(buf, 3));
  checkOverlap(buf[1]);
  const bool rebuild = buf[0] > 0.25 * skin * skin;
  if (!rebuild) search.moved(integrator.dt * std::sqrt(buf[2]));  // (a rebuild ends it anyway)
  return rebuild;
}

// ---------------------------------------------------------------------------------------------
// rebuild: history, migration, sort, ghosts, lists

void DemSolver::Impl::rebuild(bool first) {
  forces.unpack();  // the particles change order (and count): the next force pass packs them
  {
    ScopedPhase t(timers, Phase::DemMigrate);
    if (!first)
      search.packHistory(p, dec, comm.size(), [&](std::size_t b) { return forces.lend(b); });
    if (anyOutflow) removeOutflow();
    if (!incoming.empty()) {
      p.nGhost = 0;
      for (const auto& q : incoming) addParticle(q);
      incoming.clear();
    }
    exchange->migrate();
  }
  {
    ScopedPhase t(timers, Phase::DemNeighbour);
    search.sortByBin(p);
  }
  {
    ScopedPhase t(timers, Phase::DemGhost);
    exchange->buildGhosts();
  }
  {
    ScopedPhase t(timers, Phase::DemNeighbour);
    search.buildLists(p, skin, wallOn);
    search.keepPositions(p);
  }
  if (!first) ++rebuilds;
}

std::size_t DemSolver::Impl::memory() const {
  std::size_t b = 0;
  memoryParts([&](const char*, std::size_t bytes) { b += bytes; });
  return b;
}

Json DemSolver::Impl::memoryByPart() const {
  Json j = Json::object();
  forEachField(p, [&](const FieldInfo& fi, const auto* cols) {
    std::size_t b = 0;
    for (int k = 0; k < fi.components; ++k) b += cap(cols[k]);
    j["field." + std::string(fi.name)] = static_cast<double>(b);
  });
  memoryParts([&](const char* name, std::size_t bytes) {
    if (std::string_view(name) != "fields") j[name] = static_cast<double>(bytes);
  });
  return j;
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
  return impl_->integrator.dt;
}
double DemSolver::time() const {
  return impl_->time;
}
void DemSolver::holdExternalHeat(long long substeps) {
  impl_->heat.heldSubsteps = std::max(0LL, substeps);
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
  return impl_->search.bins().bs;
}
long long DemSolver::rebuildCount() const {
  return impl_->rebuilds;
}
std::size_t DemSolver::memoryBytes() const {
  return impl_->memory();
}
long long DemSolver::localContacts() const {
  return impl_->forces.tally().contacts;
}
long long DemSolver::localWallContacts() const {
  return impl_->forces.tally().walls;
}

Json DemSolver::diagnostics() const {
  const auto& m = *impl_;
  double loc[6] = {static_cast<double>(m.p.nOwned),
                   static_cast<double>(m.forces.tally().contacts),
                   static_cast<double>(m.forces.tally().walls),
                   static_cast<double>(m.p.nGhost),
                   static_cast<double>(m.search.list().nbr.size()),
                   static_cast<double>(m.memory())};
  m.comm.sumInPlace(std::span<double>(loc, 6));
  const double n = std::max(1.0, loc[0]);
  Json j;
  j["count"] = static_cast<long long>(loc[0]);
  j["contacts_per_particle"] = loc[1] / n;
  j["wall_contacts"] = static_cast<long long>(loc[2]);
  j["ghosts"] = static_cast<long long>(loc[3]);
  j["neighbors_per_particle"] = loc[4] / n;
  j["rebuilds"] = m.rebuilds;
  j["prunes"] = m.search.pruneCount();
  j["bytes_per_particle"] = loc[5] / n;
  {  // the same by part (every rank has the same parts in the same order)
    const Json parts = m.memoryByPart();
    std::vector<double> v;
    for (const auto& [k, b] : parts.items()) v.push_back(b.get<double>());
    m.comm.sumInPlace(std::span<double>(v));
    Json per = Json::object();
    std::size_t c = 0;
    for (const auto& [k, b] : parts.items()) per[k] = v[c++] / n;
    j["bytes_by_part"] = per;
  }
  j["interaction_range"] = m.rc;
  j["skin"] = m.skin;
  j["bin_size"] = {m.search.bins().bs[0], m.search.bins().bs[1], m.search.bins().bs[2]};
  j["dt"] = m.integrator.dt;
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
  if (m.heat.on) {
    // energy accounts (J): enthalpy held = enthalpy at the start + wall_heat_in + ext_heat_in +
    // inflow_enthalpy_in - outflow_enthalpy_out (the coupling's energy balance reads them);
    // energy_balance: the residual relative to the largest of |H|, |H0| and the gross flows
    const auto& h = m.heat;
    const auto& T = m.p.extra[h.iT].data[0];
    double loc[4] = {0, h.wallHeat, h.extHeat, h.outflowEnthalpy};
    double tMin = std::numeric_limits<double>::infinity(), tMax = -tMin;
    for (std::size_t i = 0; i < m.p.nOwned; ++i) {
      loc[0] += h.enthalpy(m.p, i);
      tMin = std::min(tMin, T[i]);
      tMax = std::max(tMax, T[i]);
    }
    m.comm.sumInPlace(std::span<double>(loc, 4));
    Json hj;
    hj["enthalpy"] = loc[0];
    hj["wall_heat_in"] = loc[1];
    hj["ext_heat_in"] = loc[2];
    hj["inflow_enthalpy_in"] = h.inflowEnthalpy;
    hj["outflow_enthalpy_out"] = loc[3];
    const double H0 = h.enthalpyInitial;
    hj["enthalpy_initial"] = H0;
    const double res = std::abs(loc[0] - (H0 + loc[1] + loc[2] + h.inflowEnthalpy - loc[3]));
    const double scale = std::max(
        {std::abs(loc[0]), std::abs(H0),
         std::abs(loc[1]) + std::abs(loc[2]) + std::abs(h.inflowEnthalpy) + std::abs(loc[3])});
    hj["energy_balance"] = scale > 0 ? res / scale : 0.0;
    hj["temperature_min"] = m.comm.min(tMin);
    hj["temperature_max"] = m.comm.max(tMax);
    hj["wall_temperature"] = h.wallT > 0 ? Json(h.wallT) : Json(nullptr);  // null: adiabatic
    j["heat"] = hj;
  }
  return j;
}

}  // namespace coloc::dem
