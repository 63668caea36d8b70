#include "coloc/coupling/drag.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "coloc/core/error.hpp"
#include "drag_packs.hpp"

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

COLOC_DRAG_PACKS_DEFINE(dragPacksBuild)

bool dragCoefficientsOn(DragPacks packs, DragLaw law, std::span<const double> eps,
                        std::span<const double> d, std::span<const double> slip, double rhoF,
                        double nu, std::span<double> beta) {
  if (eps.size() < beta.size() || d.size() < beta.size() || slip.size() < beta.size())
    throw Error("coupling: dragCoefficients: inputs shorter than the output");
  const bool avx512 = __builtin_cpu_supports("avx512f");
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  // Widest: the widest packs the CPU runs (drag_packs.hpp), the same choice on every rank of a
  // run on one kind of CPU.
  if (packs == DragPacks::Widest)
    packs = avx512 ? DragPacks::Avx512 : avx2 ? DragPacks::Avx2 : DragPacks::Build;
  if ((packs == DragPacks::Avx512 && !avx512) || (packs == DragPacks::Avx2 && !avx2)) return false;
  const DragLawPacks f = packs == DragPacks::Avx512 ? dragPacksAvx512
                         : packs == DragPacks::Avx2 ? dragPacksAvx2
                                                    : dragPacksBuild;
  f(law, eps.data(), d.data(), slip.data(), rhoF, nu, beta.data(), beta.size());
  return true;
}

void dragCoefficients(DragLaw law, std::span<const double> eps, std::span<const double> d,
                      std::span<const double> slip, double rhoF, double nu,
                      std::span<double> beta) {
  dragCoefficientsOn(DragPacks::Widest, law, eps, d, slip, rhoF, nu, beta);
}

}  // namespace coloc::coupling
