// Heat that leaves with its particle (issue 50): a coupled run with fluid heat, particle heat and
// convection, an inflow of hot particles through the bottom and an outflow face at the top, for
// fluid and particles alike. Particles leave part-way through a fluid step; the fluid was charged
// the whole step's q dt for each of them, so each must take the rest of its q dt out with it
// (DemSolver::holdExternalHeat). The combined energy balance of fluid and particles,
//     H_f + H_p - H_f0 - H_p0 - (face heat + wall heat + inflow enthalpy - outflow enthalpy),
// relative to the heat the phases exchanged, must close to round-off: <= 1e-12 on 1, 2 and 3
// ranks. Before the fix the particles that left had taken only the share of the step they lived
// through, and the residual was ~1e-5 of the exchange (the fluid's, the particles' and the
// exchange's own balances each closing on their own). Zero gravity and an inflow at the liquid's
// velocity carry the beads straight through; a 2 x 2 x 4 cm column of 4 x 4 x 8 cells, 0.15 s.
// The liquid is water with a heat capacity of 1000 J/(kg K) and the beads enter at 500 K, so that
// the exchanged heat is not many orders below the enthalpies whose sums set the round-off.
#include <cmath>
#include <cstdio>

#include "coupled_util.hpp"

using namespace coloc;

namespace {

const char* const kCase = R"({
  "domain": { "length": [0.02, 0.02, 0.04], "cells": [4, 4, 8] },
  "gravity": [0.0, 0.0, 0.0],
  "run": { "steps": 150 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 1e-3, "initial_velocity": [0, 0, 0.4],
             "heat": true, "conductivity": 0.6, "heat_capacity": 1000.0,
             "initial_temperature": 300.0,
             "boundary": { "zlo": { "type": "inlet", "velocity": [0, 0, 0.4], "temperature": 300.0 },
                           "zhi": { "type": "outlet", "pressure": 0.0 },
                           "xlo": { "type": "wall", "temperature": 320.0 } },
             "pressure": { "tol": 1e-10 } },
  "particles": { "dt": 5e-5, "heat": true,
    "boundary": { "zhi": "outflow" },
    "materials": [ { "density": 2700.0, "young": 1.6e5, "poisson": 0.3, "restitution": 0.9,
                     "friction": 0.3, "heat_capacity": 900.0, "conductivity": 200.0 } ],
    "inflow": [ { "face": "zlo", "patch": { "min": [0.004, 0.004], "max": [0.016, 0.016] },
                  "rate": 4000.0, "velocity": [0.0, 0.0, 0.4], "velocity_spread": 0.02,
                  "radius": 0.0005, "temperature": 500.0 } ] },
  "coupling": { "kernel": "trilinear", "drag": "difelice", "heat_transfer": "ranz_marshall" }
})";

}  // namespace

TEST(HeatLeaving, CombinedBalanceClosesAgainstTheExchange) {
  const Comm world = Comm::world();
  coupling::Simulation sim(world, test::caseFromText(kCase));
  while (!sim.finished()) sim.step();
  const Json r = sim.report(0.0);
  const Json& f = r["fluid_heat"];
  const Json& p = r["particles"]["heat"];
  double faces = 0;
  for (const auto& [face, q] : f["face_heat"].items()) faces += q.get<double>();
  const double dH = f["enthalpy"].get<double>() - f["enthalpy_initial"].get<double>() +
                    p["enthalpy"].get<double>() - p["enthalpy_initial"].get<double>();
  const double boundary = faces + p["wall_heat_in"].get<double>() +
                          p["inflow_enthalpy_in"].get<double>() -
                          p["outflow_enthalpy_out"].get<double>();
  // The heat the fluid gave the particles (its source heat is what the particles took from it).
  const double exchanged = std::abs(f["source_heat"].get<double>());
  const double residual = std::abs(dH - boundary) / exchanged;
  // What the particles received against what the fluid gave: the same heat.
  const double handOver =
      std::abs(p["ext_heat_in"].get<double>() + f["source_heat"].get<double>()) / exchanged;
  const long long out = r["particles"]["count_out"].get<long long>();
  const long long in = r["particles"]["count_in"].get<long long>();
  if (world.isRoot())
    std::printf(
        "heat leaving, %d rank(s): %lld in, %lld out, exchanged %.6g J (sum |q| dt %.6g J), "
        "combined residual %.3g, ext_heat_in + source_heat %.3g, checks.energy_balance %.3g, "
        "energy_balance_exchanged %.3g\n",
        world.size(), in, out, exchanged, r["coupling"]["heat_transfer"].value("exchanged", 0.0),
        residual, handOver, r["checks"]["energy_balance"].get<double>(),
        r["checks"].value("energy_balance_exchanged", -1.0));
  EXPECT_GT(in, 400);   // particles came in ...
  EXPECT_GT(out, 100);  // ... and left through the outflow face, mid-step
  EXPECT_GT(exchanged, 1.0);
  EXPECT_LE(residual, 1e-12);
  EXPECT_LE(handOver, 1e-12);
  EXPECT_LE(r["checks"]["heat_exchange_balance"].get<double>(), 1e-12);
  ASSERT_TRUE(r["checks"].contains("energy_balance_exchanged"));
  EXPECT_LE(r["checks"]["energy_balance_exchanged"].get<double>(), 1e-12);
}
