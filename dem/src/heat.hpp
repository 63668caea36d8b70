// dem/src/heat.hpp — particle temperature (particles.heat) as a part: lumped capacitance per
// particle, conduction through particle-particle and particle-wall contacts (Batchelor & O'Brien
// 1977), the external heat rate the coupling writes, and the energy accounts
// (docs/heat.md, "Particles").
//
// The fields are extras of the field table (ParticleStore::addField), registered only when
// particles.heat is true, so that a run without heat moves, stores and writes nothing more:
//   temperature  T (K)    ghosts (build + update), migration, state
//   heat_rate    Q (W)    the conduction sum of the last force computation (owned; no travel)
//   heat_ext     qExt (W) written by the coupling per owned particle, held over the sub-steps
//                         (like fExt): migration, state
//
// Conduction rides the force pass (force_pass.hpp, forcePass() below: the partners' lines are in
// cache there; with heat off that pass is compiled without it), in the list's order, each pair
// once with the lower-K particle first. An owned-ghost pair is computed by each rank for its own
// particle from the same operands (the ghost's T is current: ghost update), so the heat one
// particle gains is the heat the other loses, bit for bit, across ranks. conduct() is the same
// arithmetic as a pass of its own over the touching entries (frozen sub-steps, which compute no
// forces).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "coloc/dem/dem.hpp"
#include "contact.hpp"
#include "neighbour_search.hpp"

namespace coloc::dem::detail {

/// Heat conduction inside the force pass (force_pass.hpp): what it reads, and what it writes (Q
/// of the owned particles, zeroed by HeatTransfer::forcePass; the heat into the particles through
/// the walls).
struct HeatPass {
  const double* T;
  double* Q;
  const double* kPair;  // [a * nMat + b]
  const double* kWall;  // [a]
  int nMat;
  double wallT;
  bool walls;  // wallT > 0
  double wallRate = 0;
};

class HeatTransfer {
 public:
  bool on = false;                   // particles.heat
  bool conduction = true;            // particles.contact_conduction
  double wallT = 0;                  // particles.wall_temperature (0: adiabatic walls)
  std::vector<double> cp;            // per material, J/(kg K)
  std::vector<double> kPair, kWall;  // effective conductivity: [a * nMat + b], [a]
  int nMat = 0;
  std::size_t iT = 0, iQ = 0, iExt = 0;  // indices in ParticleStore::extra

  // Energy accounts (J). Local to this rank (summed by the report): wallHeat, extHeat,
  // outflowEnthalpy. Global (the same on every rank, like DemFlow's in tallies): inflowEnthalpy
  // and enthalpyInitial, the particles' enthalpy when the run started (set-up, or the state a
  // restart continues). The report's balance: enthalpy = enthalpyInitial + wallHeat + extHeat +
  // inflowEnthalpy - outflowEnthalpy, summed over the ranks.
  double wallHeat = 0, extHeat = 0, outflowEnthalpy = 0, inflowEnthalpy = 0;
  double enthalpyInitial = 0;
  /// Sub-steps the external heat rates are still meant for (DemSolver::holdExternalHeat): a
  /// particle removed meanwhile leaves with q_ext times that many sub-steps' time.
  long long heldSubsteps = 0;

  /// Reads the keys and the materials' heat properties; registers the fields when on.
  void setup(const Config& cfg, const std::vector<Material>& mats, ParticleStore& p);
  /// Q of the owned particles from the contacts at the current positions and temperatures
  /// (ghosts' T current); the wall heat rate of this rank into wallRate().
  void conduct(ParticleStore& p, const NeighbourSearch& s);
  /// Conduction inside the next force pass (with contact conduction): Q of the owned particles
  /// zeroed, the pass's inputs; the pass's wall heat rate goes back through setWallRate().
  HeatPass forcePass(ParticleStore& p) const {
    double* Q = p.extra[iQ].data[0].data();
    std::fill(Q, Q + p.nOwned, 0.0);
    return HeatPass{
        p.extra[iT].data[0].data(), Q, kPair.data(), kWall.data(), nMat, wallT, wallT > 0};
  }
  void setWallRate(double w) { wallRate_ = w; }
  /// T += dt (Q + qExt) / (m c_p) for the owned particles; the accounts advance by dt.
  void integrate(ParticleStore& p, double dt);
  /// Owned particle i leaves (outflow) in the sub-step now running, before its temperature
  /// update: the account of what it takes out, with the external heat it was due for the rest
  /// of the held sub-steps (this one included) counted in, into the particle and out with it.
  void leave(const ParticleStore& p, std::size_t i, double dt) {
    const double due = static_cast<double>(heldSubsteps) * dt * p.extra[iExt].data[0][i];
    extHeat += due;
    outflowEnthalpy += enthalpy(p, i) + due;
  }
  /// Enthalpy m c_p T of owned particle i (J).
  double enthalpy(const ParticleStore& p, std::size_t i) const {
    return p.mass[i] * cp[static_cast<std::size_t>(p.material[i])] * p.extra[iT].data[0][i];
  }
  /// Enthalpy of the owned particles (J).
  double localEnthalpy(const ParticleStore& p) const {
    double h = 0;
    for (std::size_t i = 0; i < p.nOwned; ++i) h += enthalpy(p, i);
    return h;
  }
  /// The accounts as a state holds them (this rank's shares; DemHeat), and back.
  DemHeat accounts() const {
    return {.known = true,
            .enthalpyInitial = enthalpyInitial,
            .inflowIn = inflowEnthalpy,
            .wallIn = wallHeat,
            .extIn = extHeat,
            .outflowOut = outflowEnthalpy};
  }
  void setAccounts(const DemHeat& a) {
    enthalpyInitial = a.enthalpyInitial;
    inflowEnthalpy = a.inflowIn;
    wallHeat = a.wallIn;
    extHeat = a.extIn;
    outflowEnthalpy = a.outflowOut;
  }
  /// The explicit-Euler stability check: dt <= kStableFraction m c_p / H_max for the smallest
  /// particle of each material (rMin; infinity: none) in contact with its own material and the
  /// wall at the overlap limit. ConfigError on particles.dt.
  void checkTimeStep(double dt, double overlapLimit, const std::vector<Material>& mats,
                     const std::vector<double>& rMin) const;
  static constexpr double kStableFraction = 0.1;

 private:
  double wallRate_ = 0;  // W, into the particles through the walls (last conduct)
};

}  // namespace coloc::dem::detail
