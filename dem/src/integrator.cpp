// dem/src/integrator.cpp — the velocity Verlet integration of the owned particles (Integrator,
// integrator.hpp).
#include "integrator.hpp"

#include <algorithm>
#include <cstddef>
#include <limits>

#include "pairs.hpp"

namespace coloc::dem::detail {

// While no rebuild has reordered the particles since the last force computation
// (ContactForces::packed, contact_forces.hpp),
// initialIntegrate also does the first part of the next force computation, on the data it has
// in hand: it writes the owned particles' packed rows for the force loop (pairs.hpp: Body) and,
// after its half kick, resets the force and torque sums to gravity + fExt (the same values as
// the force loop's own reset: same bits). By blocks of kIntBlock particles: the columns on the
// vector units, then the packed rows copied whole (line stores) while the block is in L1.
namespace {
constexpr std::size_t kIntBlock = 256;
}

double Integrator::initialIntegrate(ParticleStore& p, ContactForces& forces) const {
  const std::size_t n = p.nOwned;
  const double h = 0.5 * dt;
  double *X0 = p.x[0].data(), *X1 = p.x[1].data(), *X2 = p.x[2].data();
  double *V0 = p.v[0].data(), *V1 = p.v[1].data(), *V2 = p.v[2].data();
  double *W0 = p.omega[0].data(), *W1 = p.omega[1].data(), *W2 = p.omega[2].data();
  double *F0 = p.f[0].data(), *F1 = p.f[1].data(), *F2 = p.f[2].data();
  double *T0 = p.torque[0].data(), *T1 = p.torque[1].data(), *T2 = p.torque[2].data();
  const double *m = p.mass.data(), *r = p.radius.data();
  const double *E0 = p.fExt[0].data(), *E1 = p.fExt[1].data(), *E2 = p.fExt[2].data();
  const double g0 = g[0], g1 = g[1], g2 = g[2];
  Body* B = forces.bodies();
  const bool reset = forces.packed();
  // the largest squared drift velocity (NaN and inf as the largest double)
  constexpr double kBig = std::numeric_limits<double>::max();
  double v2max = 0;
  for (std::size_t b0 = 0; b0 < n; b0 += kIntBlock) {
    const std::size_t b1 = std::min(n, b0 + kIntBlock);
#pragma omp simd reduction(max : v2max)
    for (std::size_t i = b0; i < b1; ++i) {
      V0[i] += h * F0[i] / m[i], V1[i] += h * F1[i] / m[i], V2[i] += h * F2[i] / m[i];
      X0[i] += dt * V0[i], X1[i] += dt * V1[i], X2[i] += dt * V2[i];
      const double v2 = V0[i] * V0[i] + V1[i] * V1[i] + V2[i] * V2[i];
      const double c = v2 <= kBig ? v2 : kBig;
      v2max = v2max > c ? v2max : c;
      const double I = 0.4 * m[i] * r[i] * r[i];
      W0[i] += h * T0[i] / I, W1[i] += h * T1[i] / I, W2[i] += h * T2[i] / I;
      if (reset) {
        F0[i] = m[i] * g0 + E0[i], F1[i] = m[i] * g1 + E1[i], F2[i] = m[i] * g2 + E2[i];
        T0[i] = T1[i] = T2[i] = 0;
      }
    }
    if (!reset) continue;
    for (std::size_t i = b0; i < b1; ++i)
      B[i] = Body{{X0[i], X1[i], X2[i]}, r[i], {V0[i], V1[i], V2[i]}, m[i]};
  }
  return v2max;
}

void Integrator::finalIntegrate(ParticleStore& p) const {
  const std::size_t n = p.nOwned;
  const double h = 0.5 * dt;
  double *V0 = p.v[0].data(), *V1 = p.v[1].data(), *V2 = p.v[2].data();
  double *W0 = p.omega[0].data(), *W1 = p.omega[1].data(), *W2 = p.omega[2].data();
  const double *F0 = p.f[0].data(), *F1 = p.f[1].data(), *F2 = p.f[2].data();
  const double *T0 = p.torque[0].data(), *T1 = p.torque[1].data(), *T2 = p.torque[2].data();
  const double *m = p.mass.data(), *r = p.radius.data();
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    V0[i] += h * F0[i] / m[i], V1[i] += h * F1[i] / m[i], V2[i] += h * F2[i] / m[i];
    const double I = 0.4 * m[i] * r[i] * r[i];
    W0[i] += h * T0[i] / I, W1[i] += h * T1[i] / I, W2[i] += h * T2[i] / I;
  }
}

}  // namespace coloc::dem::detail
