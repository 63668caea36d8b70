#include "coloc/coupling/self_velocity.hpp"

#include <cmath>
#include <numbers>

#include "coloc/core/error.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

SelfVelocity selfVelocityFromConfig(const Config& cfg) {
  const std::string name = cfg.string("coupling.self_velocity");
  if (name == "none") return SelfVelocity::None;
  if (name != "stokeslet")
    throw ConfigError("coupling.self_velocity", "unknown correction '" + name + "'");
  if (cfg.string("coupling.kernel") != "trilinear")
    throw ConfigError(
        "coupling.self_velocity",
        "the stokeslet correction is derived for the trilinear kernel (coupling.kernel "
        "is '" +
            cfg.string("coupling.kernel") + "')");
  if (cfg.integer("coupling.smoothing_passes") != 0)
    throw ConfigError("coupling.self_velocity",
                      "the stokeslet correction is derived without smoothing (set "
                      "coupling.smoothing_passes to 0)");
  const GlobalGrid g = gridFromConfig(cfg);
  const double h0 = g.spacing(0);
  for (int d = 1; d < 3; ++d)
    if (std::abs(g.spacing(d) - h0) > 1e-9 * h0)
      throw ConfigError("coupling.self_velocity",
                        "the stokeslet correction is derived for cubic cells (domain.length / "
                        "domain.cells differ between axes)");
  return SelfVelocity::Stokeslet;
}

std::array<double, 3> selfResponse(const std::array<double, 3>& t) {
  // Per axis, the pair weights of the stencil: offset 0 with (1-t)^2 + t^2, offset 1 with
  // 2 t (1-t) (both signs; the Green's function is even in each offset for a == b).
  double w[3][2];
  for (int d = 0; d < 3; ++d) {
    w[d][0] = (1.0 - t[d]) * (1.0 - t[d]) + t[d] * t[d];
    w[d][1] = 2.0 * t[d] * (1.0 - t[d]);
  }
  std::array<double, 3> r{};
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    double s = 0;
    for (int oa = 0; oa < 2; ++oa)
      for (int ob = 0; ob < 2; ++ob)
        for (int oc = 0; oc < 2; ++oc) s += w[a][oa] * w[b][ob] * w[c][oc] * kSelfGreen[oa][ob][oc];
    r[a] = s;
  }
  return r;
}

double equivalentWidth(double r) {
  // Gaussian force density exp(-x^2 / (2 sigma^2)) / (2 pi sigma^2)^{3/2}: the Stokes velocity at
  // its centre is F (2/3) / ((2 pi)^{3/2} mu sigma) (the isotropic projection keeps 2/3).
  constexpr double pi = std::numbers::pi;
  return (2.0 / 3.0) / (std::pow(2.0 * pi, 1.5) * r);
}

double buildUp(double sigma, double nu, double t) {
  if (t <= 0) return 0.0;
  return 1.0 - sigma / std::sqrt(sigma * sigma + 2.0 * nu * t);
}

double selfMobility(const std::array<double, 3>& t, const std::array<double, 3>& dir, double h,
                    double mu, double nu, double eps, double tRun) {
  const std::array<double, 3> r = selfResponse(t);
  double c = 0;
  for (int a = 0; a < 3; ++a) {
    const double sigma = equivalentWidth(r[a]) * h;
    c += dir[a] * dir[a] * r[a] * buildUp(sigma, nu, tRun);
  }
  return c / (mu * h * eps);
}

}  // namespace coloc::coupling
