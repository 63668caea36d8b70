// Fluid-particle convection (coupling.heat_transfer): a single sphere settling at its terminal
// velocity through still water, hotter than the water, cools as the lumped-capacitance
// exponential with Ranz & Marshall's Nusselt number at its Reynolds number:
//     T_p - T_f = (T_p0 - T_f) exp(-(t - t0) / tau_T),  tau_T = m c_p / (Nu k_f pi d),
//     Nu = 2 + 0.6 Re^(1/2) Pr^(1/3),  Re = d |v_p| / nu,  Pr = rho_f nu c_f / k_f,
// within 1 % (of the decay exponent and of T_p - T_f after one tau_T). The cells are 100
// diameters wide (as in the settling test): the water the sphere heats and drags along stays
// within 1e-6 of its own temperature and velocity scale at the particle. What remains is the
// particle's backward-Euler response over each CFD step (dt / tau_T = 1/160: 0.3 % of the
// exponent). The heat the particle gives equals the heat the fluid cells receive to round-off.
// Its material is soft (E = 1 kPa) only to keep the DEM time-step check out of the way.
//
// Stiff exchange: warm spheres at rest in still air in a closed, adiabatic box, with CFD steps 10
// times the air's thermal relaxation time to the particles (dt sum H / (rho_f c_f eps V) ~ 10:
// an explicit source would overshoot by an order of magnitude). The exchange is implicit on both
// sides, so every temperature stays between the two initial ones, the total enthalpy of fluid
// and particles is constant to 1e-12, and both relax to the two-body equilibrium
// (C_f T_f0 + C_p T_p0) / (C_f + C_p).
#include <cmath>
#include <cstdio>
#include <numbers>

#include "coloc/coupling/drag.hpp"
#include "coloc/coupling/heat_transfer.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr double kPi = std::numbers::pi;

struct Sphere {
  double T = 0, v = 0;  // temperature (K), settling speed (m/s)
};

Sphere sphereOf(coupling::Simulation& sim) {
  double buf[3] = {0, 0, 0};
  const auto& p = sim.particles()->particles();
  const auto& T = p.field("temperature");
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    buf[0] += T[i];
    buf[1] += std::sqrt(p.v[0][i] * p.v[0][i] + p.v[1][i] * p.v[1][i] + p.v[2][i] * p.v[2][i]);
    buf[2] += 1.0;
  }
  sim.decomposition().comm().sumInPlace(std::span<double>(buf, 3));
  EXPECT_EQ(buf[2], 1.0);
  return {buf[0], buf[1]};
}

}  // namespace

TEST(Convection, SingleSphereCoolsAtRanzMarshallRate) {
  const double d = 1e-3, nu = 1e-6, rhoF = 1000.0, g = 9.81, kF = 0.6, cF = 4186.0;
  const double Tf = 300.0, Tp0 = 350.0;
  const double vp = kPi * d * d * d / 6.0;
  // Terminal Reynolds number 10 (Di Felice drag), as in the settling test.
  const double vTarget = 10.0 * nu / d;
  const double rhoP =
      rhoF + coupling::dragCoefficient(coupling::DragLaw::DiFelice, 1.0, d, vTarget, rhoF, nu) *
                 vTarget / (g * vp);
  const double beta =
      coupling::dragCoefficient(coupling::DragLaw::DiFelice, 1.0, d, vTarget, rhoF, nu);
  const double tau = rhoP * vp / beta;  // momentum relaxation time
  const double pr = rhoF * nu * cF / kF;
  const double H = coupling::nusselt(coupling::HeatLaw::RanzMarshall, 1.0, 10.0, pr) * kF * kPi * d;
  // The particle's heat capacity: a thermal time of 20 momentum times.
  const double tauT = 20.0 * tau, cp = H * tauT / (rhoP * vp);
  const double h = 100 * d, lx = 16 * h, lz = 24 * h;
  const double dtFluid = tau / 8, t0 = 4 * tau, t1 = t0 + tauT;
  char text[4096];
  std::snprintf(text, sizeof text, R"({
    "domain": { "length": [%.17g, %.17g, %.17g], "cells": [16, 16, 24] },
    "gravity": [0.0, 0.0, -9.81],
    "run": { "steps": 0, "end_time": %.17g },
    "fluid": { "nu": %.17g, "rho": %.17g, "dt": %.17g,
               "heat": true, "conductivity": %.17g, "heat_capacity": %.17g,
               "initial_temperature": %.17g,
               "boundary": { "zhi": { "type": "outlet", "pressure": 0.0 } },
               "pressure": { "tol": 1e-12 } },
    "particles": { "dt": %.17g, "bin_cells": 1, "heat": true,
      "materials": [ { "density": %.17g, "young": 1e3, "poisson": 0.3, "restitution": 0.9,
                       "heat_capacity": %.17g, "conductivity": 50.0 } ],
      "sources": [ { "type": "list", "positions": [%.17g, %.17g, %.17g], "radius": %.17g,
                     "velocity": [0.0, 0.0, %.17g], "temperature": %.17g } ] },
    "coupling": { "drag": "difelice", "kernel": "trilinear", "heat_transfer": "ranz_marshall" }
  })",
                lx, lx, lz, t1, nu, rhoF, dtFluid, kF, cF, Tf, dtFluid / 20, rhoP, cp,
                0.5 * lx + 0.3 * h, 0.5 * lx + 0.2 * h, 0.8 * lz, 0.5 * d, -vTarget, Tp0);
  const Config cfg = test::caseFromText(text);
  coupling::Simulation sim(Comm::world(), cfg);
  while (sim.time() < t0 * (1 - 1e-9)) sim.step();
  const Sphere a = sphereOf(sim);
  const double ta = sim.time();
  while (!sim.finished()) sim.step();
  const Sphere b = sphereOf(sim);
  const double tb = sim.time();
  // Ranz-Marshall at the sphere's own (mean) settling speed: the water around it is still.
  const double re = d * 0.5 * (a.v + b.v) / nu;
  const double Hre = coupling::nusselt(coupling::HeatLaw::RanzMarshall, 1.0, re, pr) * kF * kPi * d;
  const double rate = Hre / (rhoP * vp * cp);
  const double expected = std::exp(-rate * (tb - ta));
  const double ratio = (b.T - Tf) / (a.T - Tf);
  std::printf(
      "single sphere: Re = %.4f, Pr = %.4f, tau_T = %.5g s; (T - T_f) fell by %.6f over %.5g s, "
      "Ranz-Marshall exponential %.6f (exponent ratio %.5f)\n",
      re, pr, 1.0 / rate, ratio, tb - ta, expected, std::log(ratio) / std::log(expected));
  EXPECT_NEAR(std::log(ratio) / std::log(expected), 1.0, 0.01);
  EXPECT_NEAR(ratio / expected, 1.0, 0.01);
  EXPECT_LE(sim.heatBalance(), 1e-12);
  // The water stays at its temperature to within 1e-6 of the difference.
  const Json r = sim.report(1.0);
  EXPECT_LT(r["checks"]["heat_exchange_balance"].get<double>(), 1e-12);
  EXPECT_LT(r["checks"]["energy_balance"].get<double>(), 1e-12);
  EXPECT_LT(r["coupling"]["heat_transfer"]["biot_max"].get<double>(), 0.1);
  const auto& T = sim.fluid()->fields().T;
  double tMax = 0;
  forEach(T.interior(), [&](int i, int j, int k) { tMax = std::max(tMax, T(i, j, k)); });
  tMax = sim.decomposition().comm().max(tMax);
  EXPECT_GT(tMax, Tf);
  EXPECT_LT(tMax - Tf, 1e-6 * (Tp0 - Tf));
}

TEST(Convection, StiffExchangeStaysBoundedAndConservesEnergy) {
  const double Tf0 = 300.0, Tp0 = 400.0, rhoF = 1.2, cF = 1006.0, rhoP = 2500.0, cP = 840.0;
  const double r = 2.5e-4;
  const int n = 64;
  // 2 mm cells, one 0.5 mm sphere a cell on average: the air of a cell relaxes to its particles in
  // C_cell / sum H ~ 0.1 s, the particles in m c_p / H ~ 1.7 s, conduction between cells in
  // h^2 / alpha ~ 0.2 s; the CFD step is 1 s.
  const char* text = R"({
    "domain": { "length": [0.008, 0.008, 0.008], "cells": [4, 4, 4] },
    "gravity": [0.0, 0.0, 0.0],
    "run": { "steps": 30 },
    "fluid": { "nu": 1.5e-5, "rho": 1.2,
               "heat": true, "conductivity": 0.026, "heat_capacity": 1006.0,
               "initial_temperature": 300.0, "pressure": { "tol": 1e-12 } },
    "particles": { "dt": 2e-3, "heat": true,
      "materials": [ { "density": 2500.0, "young": 10.0, "poisson": 0.3,
                       "heat_capacity": 840.0, "conductivity": 1.0 } ],
      "sources": [ { "type": "random", "lo": [0.0005, 0.0005, 0.0005],
                     "hi": [0.0075, 0.0075, 0.0075], "count": 64, "radius": 0.00025,
                     "temperature": 400.0 } ] },
    "coupling": { "drag": "stokes", "heat_transfer": "ranz_marshall", "dem_substeps": 500 }
  })";
  // The premise: one sphere's H (Nu = 2 in still air) over one step exceeds its cell's air
  // capacity several times (an explicit source would overshoot).
  const double stiffness = 1.0 * 2.0 * 0.026 * kPi * 2 * r / (rhoF * cF * 0.002 * 0.002 * 0.002);
  ASSERT_GT(stiffness, 5.0);
  const Config cfg = test::caseFromText(text);
  coupling::Simulation sim(Comm::world(), cfg);
  const auto& comm = sim.decomposition().comm();
  const double vCell = sim.decomposition().grid().cellVolume();
  const double mP = rhoP * 4.0 / 3.0 * kPi * r * r * r;
  // Enthalpies and extremes (collective): fluid sum rho c eps V T, particles sum m c T.
  const auto measure = [&](double out[4]) {
    const auto& f = sim.fluid()->fields();
    double hf = 0, hp = 0, lo = 1e300, hi = -1e300;
    forEach(f.T.interior(), [&](int i, int j, int k) {
      hf += rhoF * cF * f.eps(i, j, k) * vCell * f.T(i, j, k);
      lo = std::min(lo, f.T(i, j, k));
      hi = std::max(hi, f.T(i, j, k));
    });
    const auto& p = sim.particles()->particles();
    const auto& T = p.field("temperature");
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      hp += mP * cP * T[i];
      lo = std::min(lo, T[i]);
      hi = std::max(hi, T[i]);
    }
    out[0] = comm.sum(hf);
    out[1] = comm.sum(hp);
    out[2] = comm.min(lo);
    out[3] = comm.max(hi);
  };
  double start[4];
  measure(start);
  // The fluid's heat capacity (eps < 1 where the particles are) and the particles'.
  const double cf = start[0] / Tf0, cp = start[1] / Tp0;
  const double teq = (cf * Tf0 + cp * Tp0) / (cf + cp);
  ASSERT_EQ(sim.particles()->globalCount(), n);
  double now[4];
  while (!sim.finished()) {
    sim.step();
    measure(now);
    ASSERT_GE(now[2], Tf0 - 1e-9) << "step " << sim.steps();
    ASSERT_LE(now[3], Tp0 + 1e-9) << "step " << sim.steps();
    ASSERT_NEAR(now[0] + now[1], start[0] + start[1], 1e-12 * (start[0] + start[1]))
        << "step " << sim.steps();
  }
  std::printf(
      "stiff exchange: C_f = %.4g J/K, C_p = %.4g J/K, T_eq = %.6f K; after %lld steps "
      "T in [%.6f, %.6f] K\n",
      cf, cp, teq, sim.steps(), now[2], now[3]);
  EXPECT_LE(sim.heatBalance(), 1e-12);
  const Json report = sim.report(1.0);
  EXPECT_LE(report["checks"]["energy_balance"].get<double>(), 1e-12);
  EXPECT_NEAR(now[2], teq, 1e-3 * (Tp0 - Tf0));
  EXPECT_NEAR(now[3], teq, 1e-3 * (Tp0 - Tf0));
}

TEST(Convection, NusseltLaws) {
  // Ranz-Marshall and Gunn at a few points (hand-evaluated), and Gunn's limit 2 at eps = 1,
  // Re = 0 (a sphere in still fluid).
  const double pr = 0.7;
  EXPECT_DOUBLE_EQ(coupling::nusselt(coupling::HeatLaw::RanzMarshall, 1.0, 0.0, pr), 2.0);
  EXPECT_NEAR(coupling::nusselt(coupling::HeatLaw::RanzMarshall, 1.0, 100.0, pr),
              2.0 + 0.6 * 10.0 * std::cbrt(0.7), 1e-14);
  EXPECT_NEAR(coupling::nusselt(coupling::HeatLaw::Gunn, 1.0, 0.0, pr), 2.0, 1e-14);
  const double eps = 0.4, re = 50.0;
  const double gunn =
      (7 - 10 * eps + 5 * eps * eps) * (1 + 0.7 * std::pow(re, 0.2) * std::cbrt(pr)) +
      (1.33 - 2.4 * eps + 1.2 * eps * eps) * std::pow(re, 0.7) * std::cbrt(pr);
  EXPECT_NEAR(coupling::nusselt(coupling::HeatLaw::Gunn, eps, re, pr), gunn, 1e-12 * gunn);
  EXPECT_EQ(coupling::nusselt(coupling::HeatLaw::None, eps, re, pr), 0.0);
  EXPECT_THROW(coupling::heatLawFromName("dittus"), ConfigError);
}
