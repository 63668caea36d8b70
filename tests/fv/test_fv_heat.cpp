// The fluid energy equation (fluid.heat, docs/heat.md "Fluid energy"), serial validations:
//  - steady conduction between two walls at fixed temperatures: the linear profile, to 1e-9 of
//    the temperature difference (the discrete steady state is exactly linear; what is left is
//    the transient's remainder exp(-pi^2 alpha t / L^2) < 1e-12 and round-off);
//  - transient conduction from a wall suddenly held at T_w into a fluid at T_0 (the far end
//    adiabatic, reached by < 1e-10 of the front): the erfc solution, max error <= 1 % of
//    |T_w - T_0| at 40 cells, and the error falls with refinement (20 -> 40 -> 80 cells);
//  - advection-diffusion of an inlet temperature step in a uniform plug flow: Ogata & Banks
//    (1961), max error <= 3 % of the step at 400 cells (first-order upwind: the error is its
//    numerical diffusion U h (1 - CFL) / 2) and it falls with refinement;
//  - a uniform temperature stays uniform (<= 1e-11 relative; the face fluxes are those of the
//    continuity equation, which holds to the pressure tolerance, 1e-13 here) while eps changes
//    every step;
//  - energy balance: enthalpy(t) - enthalpy(0) = heat through the faces + source heat, <= 1e-12
//    relative, in a closed box with a source and in an open channel (inlet, outlet, a wall at a
//    fixed temperature, a source, moving eps);
//  - the state table restores the temperature bit for bit (restart / re-balance path);
//  - missing thermal keys with fluid.heat on name the key; with fluid.heat off nothing changes.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {

struct HeatRun {
  Decomposition dec;
  Timers timers;
  fv::FluidSolver solver;
  explicit HeatRun(const Config& cfg)
      : dec(decompositionFromConfig(Comm(MPI_COMM_SELF), cfg)), solver(dec, cfg, timers) {}
};

/// A 1-D case along x: n cells on [0, 1] (3 periodic cells of the same size along y and z).
std::string slab(int n, const std::string& fluid) {
  const double h = 1.0 / n;
  return R"({"run": {"mode": "fluid"},
    "domain": {"length": [1.0, )" +
         std::to_string(3 * h) + ", " + std::to_string(3 * h) + R"(], "cells": [)" +
         std::to_string(n) + R"(, 3, 3], "periodic": {"y": true, "z": true}},
    "fluid": {"heat": true, "rho": 1.0, "heat_capacity": 1.0, )" +
         fluid + "}}";
}

double heatNumber(const Json& d, const char* key) {
  return d["fluid_heat"][key].get<double>();
}

/// Runs to time t with steps of at most dt (the last one shortened).
void runTo(fv::FluidSolver& s, double t, double dt) {
  while (s.time() < t * (1 - 1e-12)) s.step(std::min(dt, t - s.time()));
}

/// Max over the cells of the x-line j = k = 0 of |T - exact(x)|.
template <class F>
double lineError(const HeatRun& r, F&& exact) {
  const auto& T = r.solver.fields().T;
  double e = 0;
  for (int i = 0; i < r.dec.cells()[0]; ++i)
    e = std::max(e, std::fabs(T(i, 0, 0) - exact(fvtest::cellPos(r.dec, i, 0, 0)[0])));
  return e;
}

}  // namespace

TEST(FvHeat, SteadyConductionBetweenTwoWallsIsLinear) {
  const Config cfg = fvtest::config(slab(20, R"("conductivity": 1.0, "initial_temperature": 300,
      "boundary": {"xlo": {"type": "wall", "temperature": 300}, "xhi": {"type": "wall",
      "temperature": 400}})"));
  HeatRun r(cfg);
  runTo(r.solver, 3.0, 0.01);  // exp(-pi^2 * 3) = 1.4e-13
  const double err = lineError(r, [](double x) { return 300.0 + 100.0 * x; });
  std::printf("steady conduction: max |T - linear| = %.3e K (of 100 K)\n", err);
  EXPECT_LE(err, 1e-9 * 100.0);
}

namespace {
double transientError(int n) {
  // alpha = 1, the wall at x = 0 held at 400 K, fluid at 300 K, t = 0.01: sqrt(alpha t) = 0.1.
  const Config cfg = fvtest::config(slab(n, R"("conductivity": 1.0, "initial_temperature": 300,
      "boundary": {"xlo": {"type": "wall", "temperature": 400}})"));
  HeatRun r(cfg);
  runTo(r.solver, 0.01, 0.001);
  return lineError(r, [](double x) { return 400.0 - 100.0 * std::erf(x / (2 * 0.1)); }) / 100.0;
}
}  // namespace

TEST(FvHeat, TransientConductionMatchesErfcAndConverges) {
  const double e20 = transientError(20), e40 = transientError(40), e80 = transientError(80);
  std::printf("transient conduction: max error / dT = %.3e (20), %.3e (40), %.3e (80 cells)\n", e20,
              e40, e80);
  EXPECT_LE(e40, 0.01);
  EXPECT_LT(e40, 0.7 * e20);
  EXPECT_LT(e80, 0.7 * e40);
}

namespace {
double ogataBanks(double x, double t, double U, double D) {
  const double s = 2 * std::sqrt(D * t);
  const double b = U * x / D;
  // exp(b) erfc(.) without overflow: erfc(z) ~ exp(-z^2)/(z sqrt(pi)) is not needed for the
  // parameters here (b <= 100).
  return 0.5 * (std::erfc((x - U * t) / s) + std::exp(b) * std::erfc((x + U * t) / s));
}

double advectionError(int n) {
  // Plug flow U = 1 along x (periodic y, z), alpha = 0.01, inlet at 1 K into fluid at 0 K,
  // t = 0.5: the front at x = 0.5, width 2 sqrt(alpha t) = 0.14.
  const Config cfg = fvtest::config(slab(n, R"("conductivity": 0.01, "initial_temperature": 0,
      "initial_velocity": [1.0, 0, 0], "nu": 0.01,
      "boundary": {"xlo": {"type": "inlet", "velocity": [1.0, 0, 0], "temperature": 1.0},
                   "xhi": {"type": "outlet"}})"));
  HeatRun r(cfg);
  runTo(r.solver, 0.5, 0.5 / n);
  return lineError(r, [](double x) { return ogataBanks(x, 0.5, 1.0, 0.01); });
}
}  // namespace

TEST(FvHeat, InletStepInPlugFlowMatchesOgataBanks) {
  const double e200 = advectionError(200), e400 = advectionError(400);
  std::printf("advection-diffusion: max error / step = %.3e (200), %.3e (400 cells)\n", e200, e400);
  EXPECT_LE(e400, 0.03);
  EXPECT_LT(e400, 0.75 * e200);
}

namespace {
const std::string kChannel = fvtest::heatChannelCase("1e-13");

/// eps^{n+1}(t) and a heat source (W per cell) on the owned cells.
void setInputs(fv::FluidSolver& s, const Decomposition& dec, double t, double source) {
  auto& f = s.edit();
  forEach(IndexBox{{0, 0, 0}, dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(dec, i, j, k);
    f.eps(i, j, k) = fvtest::channelEps(x, t);
    f.heatSource(i, j, k) = source * (1.0 + std::sin(5 * x[0]) * std::cos(3 * x[1]));
  });
}

/// |H - H0 - faces - source| relative to the throughput sum |face heat| + |source heat|.
double throughputBalance(const Json& d) {
  const auto& h = d["fluid_heat"];
  double faces = 0, gross = std::fabs(h["source_heat"].get<double>());
  for (const auto& [k, v] : h["face_heat"].items()) {
    faces += v.get<double>();
    gross += std::fabs(v.get<double>());
  }
  const double res = h["enthalpy"].get<double>() - h["enthalpy_initial"].get<double>() - faces -
                     h["source_heat"].get<double>();
  return std::fabs(res) / gross;
}
}  // namespace

TEST(FvHeat, UniformTemperatureStaysUniformWhileEpsChanges) {
  // Every thermal condition at the same temperature, no source: T must stay 320 K.
  const Config cfg = fvtest::config(
      kChannel, {"fluid.boundary.xlo.temperature=320", "fluid.boundary.ylo.temperature=320"});
  HeatRun r(cfg);
  setInputs(r.solver, r.dec, 0.0, 0.0);
  r.solver.syncEpsOld();
  for (int n = 0; n < 15; ++n) {
    setInputs(r.solver, r.dec, r.solver.time() + 0.01, 0.0);
    r.solver.step(r.solver.nextDt());
  }
  double dev = 0;
  const auto& T = r.solver.fields().T;
  forEach(IndexBox{{0, 0, 0}, r.dec.cells()},
          [&](int i, int j, int k) { dev = std::max(dev, std::fabs(T(i, j, k) - 320.0)); });
  std::printf("uniform temperature with moving eps: max |T - T0| / T0 = %.3e\n", dev / 320.0);
  EXPECT_LE(dev / 320.0, 1e-11);
}

TEST(FvHeat, EnergyBalanceClosedBoxWithSource) {
  // A lid-driven closed box (no outlet: eps = 1), adiabatic walls, a source: the enthalpy rise
  // is the source heat. T0 = 0 so that the enthalpy is all heat added.
  const Config cfg = fvtest::config(
      kChannel,
      {"fluid.boundary.xlo={\"type\": \"wall\"}", "fluid.boundary.xhi={\"type\": \"wall\"}",
       "fluid.boundary.ylo={\"type\": \"wall\"}", "fluid.initial_temperature=0"});
  HeatRun r(cfg);
  auto& f = r.solver.edit();
  forEach(IndexBox{{0, 0, 0}, r.dec.cells()}, [&](int i, int j, int k) {
    const Real3 x = fvtest::cellPos(r.dec, i, j, k);
    f.heatSource(i, j, k) = 1e-3 * (1.0 + std::sin(5 * x[0]) * std::cos(3 * x[1]));
  });
  for (int n = 0; n < 30; ++n) r.solver.step(r.solver.nextDt());
  const Json d = r.solver.diagnostics();
  const double rel = d["checks"]["fluid_energy_balance"].get<double>();
  std::printf("closed box: source heat %.6e J, enthalpy %.6e J, balance %.2e\n",
              heatNumber(d, "source_heat"), heatNumber(d, "enthalpy"), rel);
  EXPECT_GT(heatNumber(d, "source_heat"), 0.0);
  EXPECT_LE(rel, 1e-12);
  EXPECT_LE(throughputBalance(d), 1e-12);
}

TEST(FvHeat, EnergyBalanceOpenChannelWithWallAndSource) {
  const Config cfg = fvtest::config(kChannel);
  HeatRun r(cfg);
  setInputs(r.solver, r.dec, 0.0, 0.0);
  r.solver.syncEpsOld();
  for (int n = 0; n < 20; ++n) {
    setInputs(r.solver, r.dec, r.solver.time() + 0.01, 0.02);
    r.solver.step(r.solver.nextDt());
  }
  const Json d = r.solver.diagnostics();
  const auto& fh = d["fluid_heat"]["face_heat"];
  std::printf(
      "open channel: heat in xlo %.4e, out xhi %.4e, wall ylo %.4e, source %.4e J; "
      "balance %.2e (of the enthalpy), %.2e (of the throughput)\n",
      fh["xlo"].get<double>(), fh["xhi"].get<double>(), fh["ylo"].get<double>(),
      heatNumber(d, "source_heat"), d["checks"]["fluid_energy_balance"].get<double>(),
      throughputBalance(d));
  EXPECT_GT(fh["xlo"].get<double>(), 0.0);
  EXPECT_LT(fh["xhi"].get<double>(), 0.0);
  EXPECT_LT(fh["ylo"].get<double>(), 0.0);  // the wall at 300 K cools the fluid
  EXPECT_EQ(fh["yhi"].get<double>(), 0.0);  // adiabatic
  EXPECT_LE(d["checks"]["fluid_energy_balance"].get<double>(), 1e-12);
  EXPECT_LE(throughputBalance(d), 1e-12);
}

TEST(FvHeat, StateTableRestoresTheTemperatureBitForBit) {
  // Copy the state of a run into a fresh solver through the restart table (what checkpoints
  // and re-balancing do), then step both: the temperatures stay identical.
  const Config cfg = fvtest::config(kChannel);
  HeatRun a(cfg), b(cfg);
  setInputs(a.solver, a.dec, 0.0, 0.02);
  a.solver.syncEpsOld();
  for (int n = 0; n < 5; ++n) {
    setInputs(a.solver, a.dec, a.solver.time() + 0.01, 0.02);
    a.solver.step(a.solver.nextDt());
  }
  bool sawT = false;
  std::vector<const Field3<double>*> from;
  fv::forEachStateField(std::as_const(a.solver),
                        [&](const fv::FluidSolver::StateField& sf, const Field3<double>* const* p) {
                          sawT = sawT || std::string(sf.name) == "T";
                          for (int c = 0; c < sf.components; ++c) from.push_back(p[c]);
                        });
  ASSERT_TRUE(sawT);
  std::size_t at = 0;
  fv::forEachStateField(b.solver,
                        [&](const fv::FluidSolver::StateField& sf, Field3<double>* const* p) {
                          for (int c = 0; c < sf.components; ++c) *p[c] = *from[at++];
                        });
  b.solver.restoreState(a.solver.counters());
  for (int n = 0; n < 5; ++n) {
    for (auto* s : {&a, &b}) {
      setInputs(s->solver, s->dec, s->solver.time() + 0.01, 0.02);
      s->solver.step(s->solver.nextDt());
    }
  }
  const auto& Ta = a.solver.fields().T;
  const auto& Tb = b.solver.fields().T;
  long long differ = 0;
  forEach(IndexBox{{0, 0, 0}, a.dec.cells()},
          [&](int i, int j, int k) { differ += Ta(i, j, k) != Tb(i, j, k); });
  EXPECT_EQ(differ, 0);
  const Json da = a.solver.diagnostics(), db = b.solver.diagnostics();
  EXPECT_EQ(da["fluid_heat"].dump(), db["fluid_heat"].dump());
}

TEST(FvHeat, MissingThermalKeysAreNamed) {
  const auto message = [](const std::string& json, std::vector<std::string> over) {
    try {
      const Config cfg = fvtest::config(json, over);
      HeatRun r(cfg);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(kChannel, {"fluid.boundary.xlo={\"type\": \"inlet\", \"velocity\": [1, 0, "
                               "0]}"})
                .find("fluid.boundary.xlo.temperature"),
            std::string::npos);
  for (const char* key :
       {"fluid.conductivity", "fluid.heat_capacity", "fluid.initial_temperature"}) {
    std::string json = kChannel;
    const std::string name = std::string(key).substr(6);
    const auto at = json.find("\"" + name + "\"");
    ASSERT_NE(at, std::string::npos);
    json.erase(at, json.find(',', at) + 1 - at);
    EXPECT_NE(message(json, {}).find(key), std::string::npos) << key;
  }
}

TEST(FvHeat, OffLeavesNoTemperature) {
  const Config cfg = fvtest::config(kChannel, {"fluid.heat=false"});
  HeatRun r(cfg);
  EXPECT_TRUE(r.solver.fields().T.data().empty());
  r.solver.step(r.solver.nextDt());
  const Json d = r.solver.diagnostics();
  EXPECT_FALSE(d.contains("fluid_heat"));
  EXPECT_FALSE(d["checks"].contains("fluid_energy_balance"));
}
