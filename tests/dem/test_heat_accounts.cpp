// The particles' energy accounts (particles.heat; docs/heat.md, "Particles"): the report's
// particles.heat.{enthalpy, enthalpy_initial, wall_heat_in, ext_heat_in, inflow_enthalpy_in,
// outflow_enthalpy_out} close the balance
//   enthalpy = enthalpy_initial + wall_heat_in + ext_heat_in + inflow_enthalpy_in
//              - outflow_enthalpy_out,
// reported as particles.heat.energy_balance (the residual relative to the largest of |H|, |H0|
// and the gross flows), to <= 1e-12 on 1 to 4 ranks:
//  - a closed box with hot walls (the hot bed of test_heat, settling: contacts, motion) and an
//    external heat rate on every particle (heat_ext, as the coupling writes it): the external
//    heat equals sum(heat_ext) t to 1e-12 relative, and every account agrees with a serial run
//    (MPI_COMM_SELF) to 1e-10 relative (the trajectories' round-off);
//  - the conveying channel of test_flow with heat: particles entering at 300 K through an inflow
//    patch, leaving through an outflow face, walls at 400 K: the inflow enthalpy is mass_in c_p
//    300 K to 1e-12 relative.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "dem_test_util.hpp"
#include "heat_test_util.hpp"

namespace {

using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

/// The heat rate written into heat_ext of particle `id` (W): +2e-4 for even ids, -1e-4 for odd.
double extRate(std::int64_t id) {
  return id % 2 == 0 ? 2e-4 : -1e-4;
}
void setExternalHeat(Case& c) {
  auto& p = c.p();
  auto& q = p.field("heat_ext");
  for (std::size_t i = 0; i < p.nOwned; ++i) q[i] = extRate(p.id[i]);
}

const char* const kAccounts[] = {"enthalpy",    "enthalpy_initial",   "wall_heat_in",
                                 "ext_heat_in", "inflow_enthalpy_in", "outflow_enthalpy_out"};

TEST(DemHeatAccounts, ClosedBoxWithHotWallsAndExternalHeatBalances) {
  const std::string text = demtest::heatBed(350);
  Case par(text);
  Case ser(text, kSelf, {1, 1, 1});
  setExternalHeat(par);
  setExternalHeat(ser);
  const int steps = 2000;
  for (int s = 0; s < steps; ++s) {
    par.dem->substep();
    ser.dem->substep();
  }
  const auto d = par.dem->diagnostics(), ds = ser.dem->diagnostics();
  const auto& h = d["heat"];
  double ext = 0;
  for (long id = 0; id < demtest::kHeatBedN; ++id) ext += extRate(id);
  ext *= steps * par.dem->dt();
  double vmax = 0;
  for (int k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < par.p().nOwned; ++i)
      vmax = std::max(vmax, std::fabs(par.p().v[k][i]));
  vmax = par.dec.comm().max(vmax);
  double worst = 0;
  for (const char* k : kAccounts)
    worst = std::max(worst, std::fabs(h[k].get<double>() - ds["heat"][k].get<double>()) /
                                std::max(1e-300, std::fabs(ds["heat"][k].get<double>())));
  if (par.dec.comm().isRoot())
    std::printf(
        "closed box, %d ranks: H0 %.6e J, H %.6e J, wall %.4e J, ext %.4e J (expected %.4e), "
        "balance %.2e, accounts vs serial %.2e, contacts/particle %.2f, max |v| %.3f m/s\n",
        par.dec.size(), h["enthalpy_initial"].get<double>(), h["enthalpy"].get<double>(),
        h["wall_heat_in"].get<double>(), h["ext_heat_in"].get<double>(), ext,
        h["energy_balance"].get<double>(), worst, d["contacts_per_particle"].get<double>(), vmax);
  EXPECT_LE(h["energy_balance"].get<double>(), 1e-12);
  EXPECT_LT(h["wall_heat_in"].get<double>(), 0.0);  // the floor is colder than the hot half
  EXPECT_NEAR(h["ext_heat_in"].get<double>(), ext, 1e-12 * ext);
  EXPECT_EQ(h["inflow_enthalpy_in"].get<double>(), 0.0);
  EXPECT_EQ(h["outflow_enthalpy_out"].get<double>(), 0.0);
  EXPECT_LE(worst, 1e-10);
  EXPECT_GT(d["contacts_per_particle"].get<double>(), 0.5);
  EXPECT_GT(vmax, 1e-3);  // the bed moves (settles)
}

TEST(DemHeatAccounts, ChannelWithInflowAndOutflowBalances) {
  const double cp = 0.5;
  Case c(demtest::channel(R"(, "heat": true, "wall_temperature": 400)",
                          R"(, "heat_capacity": 0.5, "conductivity": 2)",
                          R"(, "temperature": 300)"));
  for (int s = 0; s < 3000; ++s) c.dem->substep();
  const auto d = c.dem->diagnostics();
  const auto& h = d["heat"];
  const double in = d["mass_in"].get<double>() * cp * 300;
  if (c.dec.comm().isRoot())
    std::printf(
        "channel, %d ranks: %lld in, %lld out; inflow %.4e J (mass_in c_p 300 K %.4e), outflow "
        "%.4e J, wall %.3e J, H %.4e J, balance %.2e\n",
        c.dec.size(), d["count_in"].get<long long>(), d["count_out"].get<long long>(),
        h["inflow_enthalpy_in"].get<double>(), in, h["outflow_enthalpy_out"].get<double>(),
        h["wall_heat_in"].get<double>(), h["enthalpy"].get<double>(),
        h["energy_balance"].get<double>());
  EXPECT_GT(d["count_out"].get<long long>(), 10);
  EXPECT_EQ(h["enthalpy_initial"].get<double>(), 0.0);  // no particle at the start
  EXPECT_NEAR(h["inflow_enthalpy_in"].get<double>(), in, 1e-12 * in);
  EXPECT_GT(h["outflow_enthalpy_out"].get<double>(), 0.0);
  EXPECT_LE(h["energy_balance"].get<double>(), 1e-12);
}

}  // namespace
