// coloc/coupling/self_velocity.hpp — correction of the self-induced velocity at a particle
// (`coupling.self_velocity`; docs/coupling.md, "Self-induced velocity").
//
// In unresolved CFD–DEM the drag reaction a particle deposits into its kernel cells accelerates
// the fluid it samples there: u_at = u_undisturbed - c F (F the drag on the particle), so a
// particle that is not small against the cell sees too little slip. The correction follows the
// regularised-Stokeslet model of Balachandar, Liu & Lakhote (2019), J. Comput. Phys. 376:160–185:
// the disturbance at the particle is that of a Gaussian-regularised Stokeslet of width sigma,
// built up since the force was switched on by the diffusion of vorticity,
//     c(t) = R (1 - sigma / sqrt(sigma^2 + 2 nu t)) / eps,   R = (2/3) / ((2 pi)^{3/2} mu sigma),
// with the force taken as quasi-steady (its present value, switched on at the start of the run).
// R is not a fitted number: it is this solver's exact steady response (MAC grid, face averages
// of the deposit and of the sampled velocity, free space) to the trilinear deposit at the
// particle's sub-cell position, read back with the same weights — a weighted sum of the discrete
// Green's function at cell offsets 0 and 1 (kSelfGreen, computed once by FFT, docs). sigma is the
// width of the Gaussian with the same steady response, per axis.
//
// With u_und = u_at + c F and the backward-Euler particle response of Simulation::evaluateDrag,
// the drag stays of the form F = beta_eff (u_at - v~), with
//     beta_eff = beta / (1 + dt beta / m - c beta)
// (dt = 0, particles that cannot move: beta / (1 - c beta)), so the deposit of beta_eff and
// beta_eff v~ keeps the exchange exactly momentum-conserving and the fluid's drag implicit.
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

/// The Gaussian width (units of h) with the steady response `r` (units 1/(mu h)).
double equivalentWidth(double r);

/// Fraction of the steady disturbance reached a time `t` after a constant force was switched on:
/// 1 - sigma / sqrt(sigma^2 + 2 nu t) (sigma in metres).
double buildUp(double sigma, double nu, double t);

/// The self-mobility c (m/(N s), u_at = u_und - c F) of a particle with stencil offsets t, unit
/// slip direction dir, at time t_run after the start of the run, on cells of size h, in fluid of
/// dynamic viscosity mu, kinematic nu, at fluid fraction eps.
double selfMobility(const std::array<double, 3>& t, const std::array<double, 3>& dir, double h,
                    double mu, double nu, double eps, double tRun);

}  // namespace coloc::coupling
