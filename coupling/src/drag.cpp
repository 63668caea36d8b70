#include "coloc/coupling/drag.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "coloc/core/error.hpp"
#include "simd_math.hpp"

namespace coloc::coupling {

DragLaw dragLawFromName(const std::string& name) {
  if (name == "stokes") return DragLaw::Stokes;
  if (name == "difelice") return DragLaw::DiFelice;
  if (name == "gidaspow") return DragLaw::Gidaspow;
  if (name == "beetstra") return DragLaw::Beetstra;
  throw ConfigError("coupling.drag", "unknown drag law '" + name + "'");
}

const char* dragLawName(DragLaw law) {
  switch (law) {
    case DragLaw::Stokes:
      return "stokes";
    case DragLaw::DiFelice:
      return "difelice";
    case DragLaw::Gidaspow:
      return "gidaspow";
    case DragLaw::Beetstra:
      return "beetstra";
  }
  return "?";
}

double beetstraF(double eps, double re) {
  const double phi = 1.0 - eps;
  re = std::max(re, 1e-12);
  const double f0 = 10.0 * phi / (eps * eps) + eps * eps * (1.0 + 1.5 * std::sqrt(phi));
  const double num = 1.0 / eps + 3.0 * eps * phi + 8.4 * std::pow(re, -0.343);
  const double den = 1.0 + std::pow(10.0, 3.0 * phi) * std::pow(re, -(1.0 + 4.0 * phi) / 2.0);
  return f0 + 0.413 * re / (24.0 * eps * eps) * num / den;
}

double dragCoefficient(DragLaw law, double eps, double d, double slip, double rhoF, double nu) {
  constexpr double pi = std::numbers::pi;
  const double mu = rhoF * nu;
  switch (law) {
    case DragLaw::Stokes:
      return 3.0 * pi * mu * d;
    case DragLaw::DiFelice: {
      const double re = std::max(eps * d * slip / nu, 1e-12);
      const double cd = std::pow(0.63 + 4.8 / std::sqrt(re), 2);
      const double lg = 1.5 - std::log10(re);
      const double chi = 3.7 - 0.65 * std::exp(-0.5 * lg * lg);
      // Cd ~ 23/Re as Re -> 0: Cd * slip stays finite; evaluate it so that slip = 0 works.
      const double cdSlip = slip > 0 ? cd * slip : std::pow(4.8, 2) * nu / (eps * d);
      return 0.125 * pi * rhoF * d * d * cdSlip * std::pow(eps, 2.0 - chi);
    }
    case DragLaw::Gidaspow: {
      const double vp = pi * d * d * d / 6.0;
      const double phi = std::max(1.0 - eps, 1e-12);
      double b;
      if (eps < 0.8) {
        b = 150.0 * phi * phi * mu / (eps * d * d) + 1.75 * phi * rhoF * slip / d;
      } else {
        const double re = std::max(eps * d * slip / nu, 1e-12);
        // Cd * slip, finite as slip -> 0 (Cd = 24/Re (1 + 0.15 Re^0.687)).
        const double cdSlip =
            re < 1000.0 ? 24.0 * nu / (eps * d) * (1.0 + 0.15 * std::pow(re, 0.687)) : 0.44 * slip;
        b = 0.75 * cdSlip * eps * phi * rhoF / d * std::pow(eps, -2.65);
      }
      return b * vp / phi;
    }
    case DragLaw::Beetstra: {
      const double re = eps * d * slip / nu;
      return 3.0 * pi * mu * d * eps * beetstraF(eps, re);
    }
  }
  return 0.0;
}

namespace {

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
void dragPacks(std::span<const double> eps, std::span<const double> d, std::span<const double> slip,
               double rhoF, double nu, std::span<double> beta) {
  constexpr std::size_t L = simd::kLanes;
  const std::size_t n = beta.size(), full = n - n % L;
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

void dragCoefficients(DragLaw law, std::span<const double> eps, std::span<const double> d,
                      std::span<const double> slip, double rhoF, double nu,
                      std::span<double> beta) {
  if (eps.size() < beta.size() || d.size() < beta.size() || slip.size() < beta.size())
    throw Error("coupling: dragCoefficients: inputs shorter than the output");
  switch (law) {
    case DragLaw::Stokes:
      return dragPacks<DragLaw::Stokes>(eps, d, slip, rhoF, nu, beta);
    case DragLaw::DiFelice:
      return dragPacks<DragLaw::DiFelice>(eps, d, slip, rhoF, nu, beta);
    case DragLaw::Gidaspow:
      return dragPacks<DragLaw::Gidaspow>(eps, d, slip, rhoF, nu, beta);
    case DragLaw::Beetstra:
      return dragPacks<DragLaw::Beetstra>(eps, d, slip, rhoF, nu, beta);
  }
}

}  // namespace coloc::coupling
