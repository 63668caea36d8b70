// coloc/coupling/self_velocity.hpp — correction of the self-induced velocity at a particle
// (`coupling.self_velocity`; docs/coupling.md, "Self-induced velocity").
//
// In unresolved CFD–DEM the drag reaction a particle deposits into its kernel cells accelerates
// the fluid it samples there: u_at = u_undisturbed - c F (F the drag on the particle), so a
// particle that is not small against the cell sees too little slip. The correction follows
// Balachandar, Liu & Lakhote (2019), J. Comput. Phys. 376:160–185: the drag law is fed the
// undisturbed flow, the particle's own perturbation predicted and removed, with the force taken
// as quasi-steady (its present value, switched on at the start of the run). The perturbation is
// not the paper's Gaussian Stokeslet but this solver's own discrete response (nothing fitted):
//  - the unsteady free-space Green's function of the MAC Stokes operator with the face averages
//    of the deposit and of the sampled velocity, at the stencil's cell offsets (tables from
//    coupling/scripts/self_green.py), read back with the trilinear weights;
//  - with the force distribution the fluid's implicit drag gives (each stencil cell receives
//    beta_eff w_c times its own, disturbed, slip): an 8 x 8 solve per axis;
//  - the particle's own share of the sampled fluid fraction removed for the drag law, and its
//    own pressure-gradient response removed from the pressure-gradient force.
//
// With u_und = u_at + c F and the backward-Euler particle response of Simulation::evaluateDrag,
// the drag stays of the form F = beta_eff (u_at - v~), with
//     beta_eff = beta / (1 + dt beta / m - c beta)
// (dt = 0, particles that cannot move: beta / (1 - c beta)), so the deposit of beta_eff and
// beta_eff v~ keeps the exchange exactly momentum-conserving and the fluid's drag implicit.
// docs/coupling.md, "Self-induced velocity correction", derives each part.
#pragma once

#include <array>
#include <string>

#include "coloc/core/config.hpp"

namespace coloc::coupling {

enum class SelfVelocity { None, Stokeslet };

/// coupling.self_velocity, checked against the case: the correction is derived for the
/// trilinear kernel without smoothing on cubic cells; anything else is a ConfigError naming the
/// key that conflicts.
SelfVelocity selfVelocityFromConfig(const Config& cfg);

/// The discrete free-space Green's function of the fluid solver, cell-centred unit force along
/// axis a -> cell-centred velocity along a, in units of 1/(mu h), at the cell offsets (o_a, o_b,
/// o_c) with o in {0, 1}: index [o_along][o_other1][o_other2] with [0][1][0] == [0][0][1].
/// Computed by FFT of the MAC Stokes operator on periodic boxes of 32^3 to 128^3 cells, with the
/// box's O(h/L) part removed (Hasimoto's lattice sum); converged to 1e-6.
inline constexpr double kSelfGreen[2][2][2] = {{{0.1263656, 0.0430323}, {0.0430323, 0.0275958}},
                                               {{0.0954928, 0.0401291}, {0.0401291, 0.0275960}}};

/// Steady self-response R_aa (a = 0, 1, 2) in units of 1/(mu h) of a particle whose trilinear
/// stencil has the fractional offsets t[3] (kernel.hpp): sum over stencil cells c, c' of
/// w_c w_c' G(c' - c). Cross terms (a != b) cancel for the trilinear stencil.
std::array<double, 3> selfResponse(const std::array<double, 3>& t);

/// The paper's Gaussian model, for comparison (docs): the Gaussian width (units of h) with the
/// steady response `r` (units 1/(mu h)).
double equivalentWidth(double r);

/// Fraction of the steady disturbance reached a time `t` after a constant force was switched on:
/// 1 - sigma / sqrt(sigma^2 + 2 nu t) (sigma in metres).
double buildUp(double sigma, double nu, double t);

/// The solver's discrete free-space response (units 1/(mu h)) at cell offsets (along, across1,
/// across2), o in {0, 1}, a time t after a unit force was switched on, s = nu t / h^2: the
/// unsteady Stokes operator of the MAC grid (tabulated from s = 1/64 to 16 by
/// coupling/scripts/self_green.py; linear in s before, the free-space 1/sqrt(s) tail after).
double discreteGreen(int along, int across1, int across2, double s);

/// The cell-centred pressure gradient (units 1/h^3) at cell offsets (along, across1, across2)
/// of a unit cell force along the axis: its irrotational part, which the projection puts into
/// the pressure at once.
double discretePressure(int along, int across1, int across2);

struct SelfResponse {
  /// c (m/(N s)) along the slip direction: u_at = u_undisturbed - c F.
  double mobility = 0;
  /// Per axis (1/m^3): the particle's own force F makes the sampled kinematic pressure gradient
  /// differ from the undisturbed one by -pressure[a] F_a / rho_f.
  std::array<double, 3> pressure{};
};

/// The self-response of a particle with stencil offsets t, unit slip direction dir, at time
/// t_run after the start of the run, on cells of size h, in fluid of dynamic viscosity mu,
/// kinematic nu, at fluid fraction eps, whose drag the fluid takes implicitly with the
/// coefficient betaEff (the deposited one): the discrete unsteady response (discreteGreen) with
/// the force distribution the implicit drag gives, w_o (U - v~ - delta_o) in stencil cell o.
SelfResponse selfMobility(const std::array<double, 3>& t, const std::array<double, 3>& dir,
                          double h, double mu, double nu, double eps, double tRun, double betaEff);

}  // namespace coloc::coupling
