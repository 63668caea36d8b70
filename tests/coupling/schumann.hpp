// Schumann's packed bed (Schumann 1929; Anzelius 1926): the fluid and solid temperatures of a
// bed of fluid fraction eps, initially at T0, fed from x = 0 with fluid at T_in at superficial
// velocity u_s, without conduction in either phase, the phases exchanging heat with the
// volumetric coefficient h a_v (a_v = 6 (1 - eps)/d, the spheres' surface per bed volume):
//
//   eps rho_f c_f dT_f/dt + rho_f c_f u_s dT_f/dx = h a_v (T_s - T_f)
//   (1 - eps) rho_s c_s dT_s/dt                  = h a_v (T_f - T_s)
//
// In the variables y = h a_v x / (rho_f c_f u_s) (the number of transfer units up to x) and
// z = h a_v (t - eps x / u_s) / (rho_s c_s (1 - eps)) (time after the fluid front's passage, in
// units of the solid's response time) they become dtheta_f/dy = theta_s - theta_f,
// dtheta_s/dz = theta_f - theta_s with theta = (T - T0)/(T_in - T0), theta_f(0, z) = 1,
// theta_s(y, 0) = 0, whose solution is
//
//   theta_f = J(y, z),   theta_s = 1 - J(z, y)   (z > 0; both 0 before the front, z < 0),
//   J(y, z) = 1 - integral_0^y exp(-z - xi) I0(2 sqrt(z xi)) dxi
//
// (T. E. W. Schumann, "Heat transfer: a liquid flowing through a porous prism", J. Franklin
// Inst. 208 (1929) 405-416; A. Anzelius, Z. angew. Math. Mech. 6 (1926) 291; the function J of
// S. Goldstein, Proc. R. Soc. Lond. A 219 (1953) 151). Inserting I0's power series, I0(2 sqrt(z
// xi)) = sum_k (z xi)^k / k!^2, and integrating term by term: J(y, z) = sum_k e^-z z^k/k! * P(N_y
// <= k), i.e. the probability that a Poisson variable of mean y does not exceed an independent one
// of mean z. That sum is what schumannJ evaluates: every term is positive and at most 1, so it
// keeps full precision for arguments in the thousands, where I0 overflows. It satisfies J(0, z) =
// 1, J(y, 0) = exp(-y) (the fluid front, attenuated) and J(y, z) + J(z, y) = 1 + exp(-y-z) I0(2
// sqrt(yz)) (tests/coupling/test_schumann.cpp checks these and an independent quadrature).
#pragma once

#include <algorithm>
#include <cmath>

namespace coloc::test {

/// Schumann's J(y, z) for y, z >= 0 (see above); absolute error about 1e-14.
inline double schumannJ(double y, double z) {
  if (!(y > 0)) return 1.0;
  if (!(z > 0)) return std::exp(-y);
  const double m = std::max(y, z);
  // both Poisson masses are negligible (below 1e-300) beyond m + 40 sqrt(m) + 60
  const auto kMax = static_cast<long>(m + 40.0 * std::sqrt(m) + 60.0);
  const double ly = std::log(y), lz = std::log(z);
  double cdf = 0, sum = 0;
  for (long k = 0; k <= kMax; ++k) {
    const double kk = static_cast<double>(k), lg = std::lgamma(kk + 1.0);
    cdf += std::exp(kk * ly - y - lg);                       // P(N_y <= k)
    sum += std::exp(kk * lz - z - lg) * std::min(cdf, 1.0);  // P(N_z = k) P(N_y <= k)
  }
  return std::min(sum, 1.0);
}

/// The fluid's theta_f(y, z): 0 before the front (z < 0).
inline double schumannFluid(double y, double z) {
  return z < 0 ? 0.0 : schumannJ(y, z);
}

/// The solid's theta_s(y, z): 0 before the front.
inline double schumannSolid(double y, double z) {
  return z <= 0 ? 0.0 : 1.0 - schumannJ(z, y);
}

/// A bed in physical units: theta at position x (m from the inlet) and time t (s).
struct SchumannBed {
  double eps = 0.4;               // fluid fraction
  double d = 1e-3;                // particle diameter (m)
  double h = 0;                   // fluid-particle heat-transfer coefficient (W/(m^2 K))
  double rhoF = 1000, cF = 4000;  // fluid density (kg/m^3), heat capacity (J/(kg K))
  double rhoS = 2500, cS = 800;   // solid density, heat capacity
  double us = 1e-3;               // superficial velocity (m/s)

  double av() const { return 6.0 * (1.0 - eps) / d; }
  double y(double x) const { return h * av() * x / (rhoF * cF * us); }
  double z(double x, double t) const {
    return h * av() * (t - eps * x / us) / (rhoS * cS * (1.0 - eps));
  }
  double fluid(double x, double t) const { return schumannFluid(y(x), z(x, t)); }
  double solid(double x, double t) const { return schumannSolid(y(x), z(x, t)); }
};

}  // namespace coloc::test
