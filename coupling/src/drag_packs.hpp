// coupling/src/drag_packs.hpp — the drag laws on packs of particles (dragCoefficients(),
// drag.hpp), compiled once per instruction set: drag.cpp for the build's target (SSE2 in the
// portable x86-64 build), drag_avx2.cpp with -mavx2 -mfma, drag_avx512.cpp with -mavx512f;
// dragCoefficients() calls the widest one the CPU runs. Everything here has internal linkage
// (no inline function of one instruction set can stand in for another's at link time).
#pragma once

#include <cstddef>
#include <numbers>

#include "coloc/coupling/drag.hpp"
#include "simd_math.hpp"

namespace coloc::coupling {

/// beta[i] for i < n: the batched law on packs of simd::kLanes particles.
using DragLawPacks = void (*)(DragLaw law, const double* eps, const double* d, const double* slip,
                              double rhoF, double nu, double* beta, std::size_t n);
void dragPacksBuild(DragLaw, const double*, const double*, const double*, double, double, double*,
                    std::size_t);
void dragPacksAvx2(DragLaw, const double*, const double*, const double*, double, double, double*,
                   std::size_t);
void dragPacksAvx512(DragLaw, const double*, const double*, const double*, double, double, double*,
                     std::size_t);

namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp): one copy per ISA

using simd::Pack;

// One pack of particles, the same formulas as dragCoefficient() with pow(x, 2) as x * x,
// pow(a, b) as exp(b log a), log10 as log / ln 10, and branches as lane-wise selections.
template <DragLaw Law>
Pack dragPack(Pack eps, Pack d, Pack slip, double rhoF, double nu) {
  constexpr double pi = std::numbers::pi, ln10 = std::numbers::ln10;
  const double mu = rhoF * nu;
  const Pack tiny = simd::splat(1e-12), one = simd::splat(1.0);
  if constexpr (Law == DragLaw::Stokes) {
    return 3.0 * pi * mu * d;
  } else if constexpr (Law == DragLaw::DiFelice) {
    const Pack re = simd::max(eps * d * slip / nu, tiny);
    const Pack a = 0.63 + 4.8 / simd::sqrt(re);
    const Pack lg = 1.5 - simd::log(re) * (1.0 / ln10);
    const Pack chi = 3.7 - 0.65 * simd::exp(-0.5 * lg * lg);
    const Pack cdSlip = slip > 0.0 ? a * a * slip : (4.8 * 4.8) * nu / (eps * d);
    return 0.125 * pi * rhoF * d * d * cdSlip * simd::pow(eps, 2.0 - chi);
  } else if constexpr (Law == DragLaw::Gidaspow) {
    const Pack vp = pi * d * d * d / 6.0;
    const Pack phi = simd::max(1.0 - eps, tiny);
    const Pack ergun = 150.0 * phi * phi * mu / (eps * d * d) + 1.75 * phi * rhoF * slip / d;
    const Pack re = simd::max(eps * d * slip / nu, tiny);
    const Pack lowRe = 24.0 * nu / (eps * d) * (1.0 + 0.15 * simd::pow(re, simd::splat(0.687)));
    const Pack cdSlip = re < 1000.0 ? lowRe : 0.44 * slip;
    const Pack wenYu = 0.75 * cdSlip * eps * phi * rhoF / d * simd::pow(eps, simd::splat(-2.65));
    return (eps < 0.8 ? ergun : wenYu) * vp / phi;
  } else {
    const Pack phi = 1.0 - eps;
    const Pack re = simd::max(eps * d * slip / nu, tiny);
    const Pack lre = simd::log(re);
    const Pack f0 = 10.0 * phi / (eps * eps) + eps * eps * (1.0 + 1.5 * simd::sqrt(phi));
    const Pack num = one / eps + 3.0 * eps * phi + 8.4 * simd::exp(-0.343 * lre);
    // 10^(3 phi) Re^(-(1 + 4 phi) / 2) as one exp.
    const Pack den = 1.0 + simd::exp(3.0 * ln10 * phi - 0.5 * (1.0 + 4.0 * phi) * lre);
    const Pack f = f0 + 0.413 * re / (24.0 * eps * eps) * num / den;
    return 3.0 * pi * mu * d * eps * f;
  }
}

template <DragLaw Law>
void dragPacks(const double* eps, const double* d, const double* slip, double rhoF, double nu,
               double* beta, std::size_t n) {
  constexpr std::size_t L = simd::kLanes;
  const std::size_t full = n - n % L;
  for (std::size_t i = 0; i < full; i += L)
    simd::store(&beta[i], dragPack<Law>(simd::load(&eps[i]), simd::load(&d[i]),
                                        simd::load(&slip[i]), rhoF, nu));
  if (full == n) return;
  // The remainder as one padded pack through the same code (lanes never mix).
  double e[L], dd[L], s[L], b[L];
  for (std::size_t l = 0; l < L; ++l) {
    const bool in = full + l < n;
    e[l] = in ? eps[full + l] : 0.5;
    dd[l] = in ? d[full + l] : 1.0;
    s[l] = in ? slip[full + l] : 1.0;
  }
  simd::store(b, dragPack<Law>(simd::load(e), simd::load(dd), simd::load(s), rhoF, nu));
  for (std::size_t i = full; i < n; ++i) beta[i] = b[i - full];
}

}  // namespace

// The definition of one of the functions above in the translation unit of its instruction set.
#define COLOC_DRAG_PACKS_DEFINE(name)                                                         \
  void name(DragLaw law, const double* eps, const double* d, const double* slip, double rhoF, \
            double nu, double* beta, std::size_t n) {                                         \
    switch (law) {                                                                            \
      case DragLaw::Stokes:                                                                   \
        return dragPacks<DragLaw::Stokes>(eps, d, slip, rhoF, nu, beta, n);                   \
      case DragLaw::DiFelice:                                                                 \
        return dragPacks<DragLaw::DiFelice>(eps, d, slip, rhoF, nu, beta, n);                 \
      case DragLaw::Gidaspow:                                                                 \
        return dragPacks<DragLaw::Gidaspow>(eps, d, slip, rhoF, nu, beta, n);                 \
      case DragLaw::Beetstra:                                                                 \
        return dragPacks<DragLaw::Beetstra>(eps, d, slip, rhoF, nu, beta, n);                 \
    }                                                                                         \
  }

}  // namespace coloc::coupling
