// dem/src/contact.hpp — materials and the contact laws (docs/dem.md).
//
// Hertz–Mindlin (no slip) with tangential history and Coulomb cap, as in LIGGGHTS 3.x
// (normal_model hertz, tangential_model history; DCS/LIGGGHTS documentation of pair gran):
//   delta = r_i + r_j - |x_i - x_j|,  R* = r_i r_j/(r_i + r_j),  m* = m_i m_j/(m_i + m_j)
//   1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j,  1/G* = 2(2 - nu_i)(1 + nu_i)/E_i + (same j)
//   S_n = 2 E* sqrt(R* delta),  S_t = 8 G* sqrt(R* delta)
//   k_n = 4/3 E* sqrt(R* delta),  k_t = S_t
//   beta = ln e / sqrt(ln^2 e + pi^2),  gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),
//   gamma_t = -2 sqrt(5/6) beta sqrt(S_t m*)
//   F_n = (k_n delta - gamma_n v_n) n       (n from j to i, v_n = (v_i - v_j).n; no force limit,
//                                            as LIGGGHTS' default: the restitution is then e
//                                            exactly, independent of the impact velocity)
//   shear: projected on the current tangent plane, then += v_t dt;  F_t = -k_t shear
//   if |F_t| > mu |F_n|:  F_t scaled to mu |F_n| and shear = -F_t/k_t (no damping while sliding)
//   else F_t -= gamma_t v_t
// Linear spring–dashpot: k_n from the case, k_t = ratio * k_n, gamma = -2 beta sqrt(k m*)
// (critical-damping fraction from e; Cundall & Strack 1979, Tsuji et al. 1992), same history,
// same Coulomb cap. Rolling resistance (optional): constant directional torque
// T_r = -mu_r R* |F_n| w/|w| with w = omega_i - omega_j (Ai et al. 2011, model A / LIGGGHTS cdt).
// Walls: the same law with R_wall, m_wall -> infinity (R* = r_i, m* = m_i) and the wall's material.
// Pair values of e, mu, mu_r between two materials: arithmetic means (a documented choice; the
// cases of this project use one material).
#pragma once

#include <cmath>
#include <vector>

namespace coloc::dem::detail {

struct Material {
  double density = 2500, young = 1e7, poisson = 0.3, restitution = 0.9, friction = 0.5,
         rollingFriction = 0.0;
  double heatCapacity = 0, conductivity = 0;  // J/(kg K), W/(m K); 0: not given (particles.heat)
};

enum class Model { HertzMindlin, Linear };

/// Coefficients of one material pair (or particle–wall pair).
struct PairCoeff {
  double Estar = 0, Gstar = 0;
  double dampH = 0;  // -2 sqrt(5/6) beta  (Hertz)
  double dampL = 0;  // -2 beta            (linear)
  double mu = 0, muR = 0;
  double tOverN = 0;      // sqrt(S_t/S_n) = sqrt(4 G*/E*): gamma_t = tOverN * gamma_n (Hertz)
  double kn = 0, kt = 0;  // linear model
  double restitution = 1;
};

inline double betaOf(double e) {
  const double le = std::log(e);
  return le / std::sqrt(le * le + M_PI * M_PI);
}

inline PairCoeff mix(const Material& a, const Material& b, double linKn, double linKtRatio) {
  PairCoeff c;
  c.Estar = 1.0 / ((1 - a.poisson * a.poisson) / a.young + (1 - b.poisson * b.poisson) / b.young);
  c.Gstar = 1.0 / (2 * (2 - a.poisson) * (1 + a.poisson) / a.young +
                   2 * (2 - b.poisson) * (1 + b.poisson) / b.young);
  c.tOverN = std::sqrt(4.0 * c.Gstar / c.Estar);
  c.restitution = 0.5 * (a.restitution + b.restitution);
  const double beta = betaOf(c.restitution);
  c.dampH = -2.0 * std::sqrt(5.0 / 6.0) * beta;
  c.dampL = -2.0 * beta;
  c.mu = 0.5 * (a.friction + b.friction);
  c.muR = 0.5 * (a.rollingFriction + b.rollingFriction);
  c.kn = linKn;
  c.kt = linKtRatio * linKn;
  return c;
}

// The contact law itself has internal linkage: the force pass is compiled once per instruction
// set (force_pass.hpp), and no inline function of one may stand in for the other's at link time.
namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp)

inline double dot3(const double* a, const double* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline void cross3(const double* a, const double* b, double* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/// The contact law for one pair, computed once (Newton's third law).
///  n: unit normal from j (or the wall) to i;  delta > 0: overlap;  vr = v_i - v_j;
///  wsum = r_i omega_i + r_j omega_j (contact-point rotation, r_j omega_j = 0 for a wall);
///  wrel = omega_i - omega_j (rolling resistance);  shear: history (updated when `update`).
/// The results are returned instead of accumulated, so that each side adds them in its own
/// canonical order:  force on i: +Fp, on j: -Fp;  torque on i: -r_i nxft - roll, on j: -r_j nxft +
/// roll (nxft = n x F_t, roll = the rolling-resistance torque on i, zero when mu_r = 0). Returns
/// |F_n|.
/// Branch-free (both sides of the Coulomb cap and of the rolling test are computed and one is
/// selected; the unselected one may be inf/NaN and is never used), so that the pair loop of
/// pairs.hpp vectorises across pairs; each selected value is the one the branchy form computes.
template <Model M, bool Rolling = true>
inline double pairForce(const PairCoeff& c, double dt, bool update, const double* n, double delta,
                        double Reff, double meff, const double* vr, const double* wsum,
                        const double* wrel, double* shear, double* Fp, double* nxft, double* roll) {
  double kn, kt, gn, gt;
  if constexpr (M == Model::HertzMindlin) {
    const double sq = std::sqrt(Reff * delta);
    const double Sn = 2.0 * c.Estar * sq, St = 8.0 * c.Gstar * sq;
    kn = (2.0 / 3.0) * Sn;
    kt = St;
    gn = c.dampH * std::sqrt(Sn * meff);
    gt = c.tOverN * gn;
  } else {
    kn = c.kn;
    kt = c.kt;
    gn = c.dampL * std::sqrt(kn * meff);
    gt = c.dampL * std::sqrt(kt * meff);
  }
  const double vn = dot3(vr, n);
  const double Fn = kn * delta - gn * vn;
  double wxn[3];
  cross3(wsum, n, wxn);
  const double vt[3] = {vr[0] - vn * n[0] - wxn[0], vr[1] - vn * n[1] - wxn[1],
                        vr[2] - vn * n[2] - wxn[2]};
  double s[3] = {shear[0], shear[1], shear[2]};
  const double sn = dot3(s, n);
  for (int k = 0; k < 3; ++k) {
    const double moved = s[k] + (vt[k] * dt - sn * n[k]);
    s[k] = update ? moved : s[k];
  }
  double Ft[3] = {-kt * s[0], -kt * s[1], -kt * s[2]};
  const double ftMax = c.mu * std::fabs(Fn);
  const double ft2 = dot3(Ft, Ft);
  const bool slip = ft2 > ftMax * ftMax;
  const double ratio = ftMax / std::sqrt(ft2);  // used only when slipping (ft2 > 0 then)
  const bool reset = slip & update & (kt > 0);  // & not &&: no branch
  for (int k = 0; k < 3; ++k) {
    const double capped = Ft[k] * ratio;
    const double damped = Ft[k] - gt * vt[k];
    const double back = -capped / kt;
    Ft[k] = slip ? capped : damped;
    shear[k] = reset ? back : s[k];
  }
  for (int k = 0; k < 3; ++k) Fp[k] = Fn * n[k] + Ft[k];
  cross3(n, Ft, nxft);
  if constexpr (!Rolling) return std::fabs(Fn);
  const double w = std::sqrt(dot3(wrel, wrel));
  const double rs = c.muR * Reff * std::fabs(Fn) / w;
  const bool rolls = (c.muR > 0) & (w > 0);
  for (int k = 0; k < 3; ++k) {
    const double t = rs * wrel[k];
    roll[k] = rolls ? t : 0.0;
  }
  return std::fabs(Fn);
}

/// Force and torque on particle i from one contact (walls, single-sided use): pairForce added
/// to F and, about i's centre, to T; returns |F_n| (for diagnostics).
template <Model M>
inline double contactForce(const PairCoeff& c, double dt, bool update, const double* n,
                           double delta, double Reff, double meff, double ri, const double* vr,
                           const double* wsum, const double* wrel, double* shear, double* F,
                           double* T) {
  double Fp[3], nxft[3], roll[3];
  const double fn =
      pairForce<M>(c, dt, update, n, delta, Reff, meff, vr, wsum, wrel, shear, Fp, nxft, roll);
  for (int k = 0; k < 3; ++k) F[k] += Fp[k];
  // torque about i's centre: (-r_i n) x F_t, then rolling resistance
  for (int k = 0; k < 3; ++k) T[k] -= ri * nxft[k];
  for (int k = 0; k < 3; ++k) T[k] -= roll[k];
  return fn;
}

}  // namespace

/// Elastic energy stored in the normal spring at overlap delta.
inline double normalEnergy(Model m, const PairCoeff& c, double delta, double Reff) {
  if (m == Model::HertzMindlin)
    return (8.0 / 15.0) * c.Estar * std::sqrt(Reff) * std::pow(delta, 2.5);
  return 0.5 * c.kn * delta * delta;
}

}  // namespace coloc::dem::detail
