// Frozen particles keep their heat physics (run.mode dummy_dem; issue 31, packed-bed heating):
// a frozen sub-step with particles.heat refreshes the ghosts' temperatures, conducts through the
// contacts of the frozen positions and integrates T with the held heat_ext, so a fixed bed can be
// heated. Checked against the same particles not frozen but at rest (no gravity, zero velocity,
// every sphere touching its neighbours at the same overlap so that the contact forces cancel):
//  - a periodic chain of four spheres of two materials (contacts across the rank face and the
//    periodic face on 2 ranks), and a periodic 4 x 4 x 4 lattice of two materials (six contacts
//    per sphere) with an external heat rate on some particles: frozen = at rest to 1e-12 of
//    the 100 K difference (the at-rest forces cancel only to round-off);
//  - the frozen lattice: enthalpy change = accumulated external heat to 1e-12 relative, and
//    2 ranks = a serial run to 1e-12 of 100 K; nothing moves (bitwise);
//  - with particles.heat off a frozen sub-step only advances the clock (positions, velocities
//    bitwise, no field).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dem_test_util.hpp"
#include "heat_test_util.hpp"

namespace {

using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

/// T by id over all ranks (n ids).
std::vector<double> temperatures(Case& c, long n) {
  std::vector<double> t(static_cast<std::size_t>(n), 0.0);
  const auto& T = c.p().field("temperature");
  for (std::size_t i = 0; i < c.p().nOwned; ++i) t[static_cast<std::size_t>(c.p().id[i])] = T[i];
  c.dec.comm().sumInPlace(std::span<double>(t));
  return t;
}

double maxDiff(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (std::size_t k = 0; k < a.size(); ++k) d = std::max(d, std::fabs(a[k] - b[k]));
  return d;
}

// r = 1 mm, spacing s = 2r - delta, delta = 10 um; materials 0 (k 1, c_p 1) and 1 (k 3, c_p 2).
constexpr double kR = 1e-3, kDelta = 1e-5, kS = 2 * kR - kDelta;

/// A periodic simple cubic lattice of 4 x 4 x 4 spheres at spacing s (each touches six
/// neighbours at the overlap delta): the half x < 2s of material 0 at 400 K, the other half of
/// material 1 at 300 K. `heat` false: particles.heat off.
std::string latticeCase(bool heat = true) {
  const double L = 4 * kS;
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"({
  "domain": {"length": [%.17g, %.17g, %.17g], "cells": [4, 4, 4],
             "periodic": {"x": true, "y": true, "z": true}},
  "particles": {
    "dt": 1e-5, "heat": %s, "contact_conduction": true,
    "materials": [{"density": 2500, "young": 1e7, "heat_capacity": 1, "conductivity": 1},
                  {"density": 2000, "young": 1e7, "heat_capacity": 2, "conductivity": 3}],
    "sources": [{"type": "lattice", "material": 0, "radius": 0.001, "temperature": 400,
                 "lo": [%.17g, %.17g, %.17g], "counts": [2, 4, 4],
                 "spacing": [%.17g, %.17g, %.17g]},
                {"type": "lattice", "material": 1, "radius": 0.001, "temperature": 300,
                 "lo": [%.17g, %.17g, %.17g], "counts": [2, 4, 4],
                 "spacing": [%.17g, %.17g, %.17g]}]
  }
})",
                L, L, L, heat ? "true" : "false", 0.5 * kS, 0.5 * kS, 0.5 * kS, kS, kS, kS,
                2.5 * kS, 0.5 * kS, 0.5 * kS, kS, kS, kS);
  return buf;
}
constexpr long kLatticeN = 64;

/// An external heat rate (W) on the particles with id % 5 == 0, as the coupling writes it.
void setExternalHeat(Case& c) {
  auto& E = c.p().field("heat_ext");
  for (std::size_t i = 0; i < c.p().nOwned; ++i) E[i] = c.p().id[i] % 5 == 0 ? 2e-4 : 0.0;
}

/// Largest |v| of the owned particles (collective).
double maxSpeed(Case& c) {
  double v = 0;
  for (std::size_t i = 0; i < c.p().nOwned; ++i)
    for (int d = 0; d < 3; ++d) v = std::max(v, std::fabs(c.p().v[d][i]));
  return c.dec.comm().max(v);
}

TEST(DemHeatFrozen, ChainFrozenEqualsAtRest) {
  const int P = coloc::Comm::world().size();
  const coloc::Int3 dims{P, 1, 1};  // contacts straddle the rank face and the periodic face
  Case frozen(demtest::chainCase(), coloc::Comm::world(), dims),
      rest(demtest::chainCase(), coloc::Comm::world(), dims);
  frozen.dem->setFrozen(true);
  const auto t0 = temperatures(frozen, 4);
  const auto x0 = demtest::table(frozen, 4);
  for (int s = 0; s < 2000; ++s) {
    frozen.dem->substep();
    rest.dem->substep();
  }
  const auto tf = temperatures(frozen, 4), tr = temperatures(rest, 4);
  const double d = maxDiff(tf, tr) / 100.0;
  const double dT0 = 0.5 * (t0[0] + t0[1] - t0[2] - t0[3]);
  const double dT1 = 0.5 * (tf[0] + tf[1] - tf[2] - tf[3]);
  if (frozen.dec.comm().isRoot())
    std::printf("chain, %d ranks: frozen vs at rest max |dT|/100 K = %.3e; dT %.3f -> %.3f K\n", P,
                d, dT0, dT1);
  EXPECT_LT(d, 1e-12);
  EXPECT_LT(dT1, 0.5 * dT0);                 // the temperatures did evolve
  EXPECT_EQ(demtest::table(frozen, 4), x0);  // nothing moved
  EXPECT_EQ(frozen.dem->time(), rest.dem->time());
  EXPECT_LT(maxSpeed(rest), 1e-6);  // the reference is at rest
}

TEST(DemHeatFrozen, LatticeFrozenEqualsAtRestAndSerial) {
  const int steps = 1500;
  Case frozen(latticeCase()), rest(latticeCase()), serial(latticeCase(), kSelf, {1, 1, 1});
  frozen.dem->setFrozen(true);
  serial.dem->setFrozen(true);
  for (Case* c : {&frozen, &rest, &serial}) setExternalHeat(*c);
  const double E0 = frozen.dem->diagnostics()["heat"]["enthalpy"].get<double>();
  const auto x0 = demtest::table(frozen, kLatticeN);
  for (int s = 0; s < steps; ++s) {
    frozen.dem->substep();
    rest.dem->substep();
    serial.dem->substep();
  }
  const auto tf = temperatures(frozen, kLatticeN), tr = temperatures(rest, kLatticeN),
             ts = temperatures(serial, kLatticeN);
  const auto diag = frozen.dem->diagnostics();
  const double E1 = diag["heat"]["enthalpy"].get<double>();
  const double Q = diag["heat"]["ext_heat_in"].get<double>();
  const double dRest = maxDiff(tf, tr) / 100.0, dSerial = maxDiff(tf, ts) / 100.0;
  const double balance = std::fabs(E1 - E0 - Q) / E0;
  const double spread =
      *std::max_element(tf.begin(), tf.end()) - *std::min_element(tf.begin(), tf.end());
  if (frozen.dec.comm().isRoot())
    std::printf(
        "lattice, %d ranks: frozen vs at rest %.3e, vs serial %.3e (max |dT|/100 K); "
        "|E1 - E0 - Q_ext|/E0 = %.2e (Q_ext %.4e J); T spread %.3f K\n",
        frozen.dec.size(), dRest, dSerial, balance, Q, spread);
  EXPECT_LT(dRest, 1e-12);
  EXPECT_LT(dSerial, 1e-12);
  EXPECT_LT(balance, 1e-12);
  EXPECT_GT(Q, 0.0);
  EXPECT_LT(spread, 90.0);  // conduction moved heat between the halves
  EXPECT_EQ(demtest::table(frozen, kLatticeN), x0);
  EXPECT_LT(maxSpeed(rest), 1e-6);
}

TEST(DemHeatFrozen, HeatOffFrozenOnlyAdvancesTheClock) {
  Case c(latticeCase(false));
  c.dem->setFrozen(true);
  EXPECT_TRUE(c.p().extra.empty());
  const auto x0 = demtest::table(c, kLatticeN);
  for (int s = 0; s < 10; ++s) c.dem->substep();
  EXPECT_EQ(demtest::table(c, kLatticeN), x0);
  EXPECT_EQ(c.dem->time(), 10 * c.dem->dt());
  EXPECT_FALSE(c.dem->diagnostics().contains("heat"));
}

}  // namespace
