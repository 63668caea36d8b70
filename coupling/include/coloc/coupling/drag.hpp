// coloc/coupling/drag.hpp — fluid–particle drag laws.
//
// Every law returns the coefficient beta (kg/s) of one particle, such that the drag force on it is
//     F_drag = beta * (u_f - v_p),
// with u_f the interstitial fluid velocity at the particle, v_p the particle velocity, eps the
// fluid fraction at the particle, d the diameter, slip = |u_f - v_p|, rho_f the fluid density and
// nu its kinematic viscosity (mu = rho_f nu). The pressure-gradient (buoyancy) force -V_p grad p
// is separate ("model A" / "set II", docs/fv.md).
//
// Stokes      beta = 3 pi mu d                                  (creeping flow, any eps)
// Di Felice   Di Felice (1994), Int. J. Multiphase Flow 20:153, in the form used by CFDEM:
//             Re = eps d slip / nu, Cd = (0.63 + 4.8/sqrt(Re))^2,
//             chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2),
//             beta = (pi/8) Cd rho_f d^2 slip eps^(2 - chi)
// Gidaspow    Gidaspow (1994), Multiphase Flow and Fluidization: interphase coefficient per unit
//             volume  B = 150 (1-eps)^2 mu/(eps d^2) + 1.75 (1-eps) rho_f slip/d   for eps < 0.8
//             (Ergun), B = 3/4 Cd eps (1-eps) rho_f slip/d eps^-2.65 for eps >= 0.8 (Wen & Yu
//             1966) with Re = eps d slip/nu, Cd = 24/Re (1 + 0.15 Re^0.687) (Re < 1000), 0.44
//             above; one particle gets beta = B V_p / (1 - eps).
// Beetstra    Beetstra, van der Hoef & Kuipers (2007), AIChE J. 53:489, eq. for the normalised
//             drag F(eps, Re) with Re = eps d slip / nu (superficial-velocity Reynolds number):
//             F = 10 (1-eps)/eps^2 + eps^2 (1 + 1.5 sqrt(1-eps))
//                 + 0.413 Re / (24 eps^2) * (1/eps + 3 eps (1-eps) + 8.4 Re^-0.343)
//                                          / (1 + 10^(3 (1-eps)) Re^-(1 + 4 (1-eps))/2)
//             beta = 3 pi mu d eps F     (F -> 1, Stokes, as eps -> 1 and Re -> 0).
// For slip -> 0 every law tends to its finite creeping-flow limit (Re is floored at 1e-12).
#pragma once

#include <span>
#include <string>

namespace coloc::coupling {

enum class DragLaw { Stokes, DiFelice, Gidaspow, Beetstra };

DragLaw dragLawFromName(const std::string& name);
const char* dragLawName(DragLaw law);

/// beta (kg/s) of one particle: F_drag = beta (u_f - v_p).
double dragCoefficient(DragLaw law, double eps, double d, double slip, double rhoF, double nu);

/// beta of n = beta.size() particles at once (eps, d, slip: at least n values each; rhoF and nu
/// as above): the same laws evaluated with vectorised maths (SLEEF, 1 ulp a function) on packs
/// of particles, what a coupled run uses. Equal to dragCoefficient() to within 1e-13 relative
/// (pow(a, b) as exp(b log a), log10 as log / ln 10); each particle's value depends on its own
/// inputs only (a partial last pack is padded), so it is the same whatever n and the particle's
/// position in the arrays. The packs are the widest the CPU runs (8 lanes with AVX-512F, 4 with
/// AVX2 + FMA, else the build's target: 2 with SSE2), chosen at run time also in the portable
/// build; values may differ in the last bits between those. No allocation.
void dragCoefficients(DragLaw law, std::span<const double> eps, std::span<const double> d,
                      std::span<const double> slip, double rhoF, double nu, std::span<double> beta);

/// The instruction sets dragCoefficients() may use: Widest (what it uses), Build (the build's
/// target, SSE2 in the portable build), Avx2, Avx512.
enum class DragPacks { Widest, Build, Avx2, Avx512 };
/// dragCoefficients() on the given packs (tests compare them); false (and nothing computed) where
/// the CPU lacks the instructions.
bool dragCoefficientsOn(DragPacks packs, DragLaw law, std::span<const double> eps,
                        std::span<const double> d, std::span<const double> slip, double rhoF,
                        double nu, std::span<double> beta);

/// Beetstra's normalised drag F(eps, Re) (exposed for tests).
double beetstraF(double eps, double re);

}  // namespace coloc::coupling
