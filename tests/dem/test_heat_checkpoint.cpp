// Particle temperatures and energy accounts (particles.heat) through a checkpoint file
// (docs/heat.md, "Particles"):
//  - a bed with a hot half run 200 sub-steps, its state written by writeDemState and read back
//    by readDemState (an even split of the rows, not the writer's); the restored solver continues
//    the temperatures bit for bit against the run that wrote it, 200 sub-steps on;
//  - a file without the accounts (written before them) restarts them at zero from the enthalpy
//    it restores, and the balance closes;
//  - the conveying channel with heat (inflow at 300 K, outflow, walls at 400 K, an external heat
//    rate on every particle), checkpointed at step 2000 on 2 ranks (1 on one rank): restarted on
//    the same ranks, its temperatures and every account (particles.heat.*) equal the run that went
//    on, bit for bit, 1000 sub-steps later; restarted on every rank of the test (3), they agree
//    to 1e-12 relative, and the balance closes to 1e-12.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "checkpoint_test_util.hpp"
#include "dem_test_util.hpp"
#include "heat_test_util.hpp"

namespace {

TEST(DemHeat, CheckpointFileContinuesTemperatures) {
  demtest::Case a(demtest::heatBed(350));
  const auto& comm = a.dec.comm();
  const long n = demtest::kHeatBedN;
  for (int s = 0; s < 200; ++s) a.dem->substep();
  coloc::dem::DemSolver b(a.dec, a.cfg, a.timers,
                          demtest::throughFile(comm, "heat", a.dem->saveState()));
  EXPECT_EQ(demtest::fieldById(b.particles(), comm, n), demtest::fieldById(a.p(), comm, n));
  for (int s = 0; s < 200; ++s) {
    a.dem->substep();
    b.substep();
  }
  const auto ta = demtest::fieldById(a.p(), comm, n),
             tb = demtest::fieldById(b.particles(), comm, n);
  long differ = 0;
  double spread = 0;
  for (long k = 0; k < n; ++k) {
    differ += ta[static_cast<std::size_t>(k)] != tb[static_cast<std::size_t>(k)];
    spread = std::max(spread, std::fabs(ta[static_cast<std::size_t>(k)] - 350.0));
  }
  if (comm.isRoot())
    std::printf("checkpoint file, %d ranks: %ld of %ld temperatures differ after 200 steps\n",
                comm.size(), differ, n);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(spread, 1.0);  // not trivially equal
}

TEST(DemHeat, AFileWithoutAccountsRestartsThemFromTheRestoredEnthalpy) {
  // a state without accounts (as a checkpoint written before them): the restart counts from
  // zero, from the enthalpy it restores, and its balance closes
  demtest::Case a(demtest::heatBed(350));
  const auto& comm = a.dec.comm();
  for (int s = 0; s < 100; ++s) a.dem->substep();
  coloc::dem::DemState st = a.dem->saveState();
  st.heat = coloc::dem::DemHeat{};  // not known: writeDemState writes no accounts
  coloc::dem::DemSolver b(a.dec, a.cfg, a.timers, demtest::throughFile(comm, "heat_old", st));
  const auto h0 = b.diagnostics()["heat"];
  const double H = h0["enthalpy"].get<double>();
  EXPECT_NEAR(h0["enthalpy_initial"].get<double>(), H, 1e-15 * H);
  EXPECT_EQ(h0["wall_heat_in"].get<double>(), 0.0);
  for (int s = 0; s < 100; ++s) b.substep();
  const auto h1 = b.diagnostics()["heat"];
  EXPECT_NE(h1["wall_heat_in"].get<double>(), 0.0);
  EXPECT_LE(h1["energy_balance"].get<double>(), 1e-12);
}

// The channel with heat; ids stay below kIds (20,000 particles/s for 30 ms).
const std::string kChannel =
    demtest::channel(R"(, "heat": true, "wall_temperature": 400)",
                     R"(, "heat_capacity": 0.5, "conductivity": 2)", R"(, "temperature": 300)");
constexpr long kIds = 1000;
const char* const kAccounts[] = {"enthalpy",    "enthalpy_initial",   "wall_heat_in",
                                 "ext_heat_in", "inflow_enthalpy_in", "outflow_enthalpy_out"};

/// The external heat rate of every owned particle (W), by id, as the coupling writes it before
/// a step; then the step.
void step(coloc::dem::DemSolver& s) {
  auto& p = s.particles();
  auto& q = p.field("heat_ext");
  for (std::size_t i = 0; i < p.nOwned; ++i) q[i] = p.id[i] % 2 == 0 ? 2e-4 : -1e-4;
  s.substep();
}

/// What a run ends with: its accounts (report) and temperatures by id, on the rank 0 of its
/// communicator.
struct End {
  coloc::Json heat;
  std::vector<double> T;
};
End endOf(coloc::dem::DemSolver& s, const coloc::Comm& comm) {
  return {s.diagnostics()["heat"], demtest::fieldById(s.particles(), comm, kIds)};
}

TEST(DemHeat, AccountsContinueThroughACheckpointOnAnyRanks) {
  const coloc::Comm world = coloc::Comm::world();
  const int W = std::min(2, world.size());  // the ranks that write the checkpoint
  MPI_Comm raw = MPI_COMM_NULL;
  MPI_Comm_split(world.raw(), world.rank() < W ? 0 : MPI_UNDEFINED, world.rank(), &raw);
  const std::string path = demtest::tempFile(world, "heat_accounts");
  const int k = 2000, m = 1000;
  std::optional<End> ref, same, other;
  if (raw != MPI_COMM_NULL) {
    const coloc::Comm wc(raw);
    demtest::Case a(kChannel, wc);
    for (int s = 0; s < k; ++s) step(*a.dem);
    demtest::writeState(wc, path, a.dem->saveState());
    for (int s = 0; s < m; ++s) step(*a.dem);  // the run that went on
    ref = endOf(*a.dem, wc);
    coloc::dem::DemSolver b(a.dec, a.cfg, a.timers, demtest::readState(wc, path));
    for (int s = 0; s < m; ++s) step(b);
    same = endOf(b, wc);
  }
  if (world.size() != W) {  // a restart on all ranks
    const coloc::Config cfg = demtest::config(kChannel);
    const coloc::Decomposition dec = coloc::decompositionFromConfig(world, cfg);
    coloc::Timers timers;
    coloc::dem::DemSolver c(dec, cfg, timers, demtest::readState(world, path));
    for (int s = 0; s < m; ++s) step(c);
    other = endOf(c, world);
  }
  demtest::removeFile(world, path);
  if (raw != MPI_COMM_NULL) MPI_Comm_free(&raw);
  if (!world.isRoot()) return;
  const auto& h = ref->heat;
  std::printf("channel with heat, checkpoint on %d ranks at step %d, %d steps on:", W, k, m);
  for (const char* a : kAccounts) std::printf(" %s %.6e J", a, h[a].get<double>());
  std::printf(", balance %.2e\n", h["energy_balance"].get<double>());
  EXPECT_GT(h["outflow_enthalpy_out"].get<double>(), 0.0);
  EXPECT_NE(h["wall_heat_in"].get<double>(), 0.0);
  EXPECT_LE(h["energy_balance"].get<double>(), 1e-12);
  // the same ranks: bit for bit
  for (const char* a : kAccounts) EXPECT_EQ(same->heat[a].get<double>(), h[a].get<double>()) << a;
  EXPECT_EQ(same->heat["energy_balance"].get<double>(), h["energy_balance"].get<double>());
  long differ = 0;
  for (std::size_t i = 0; i < ref->T.size(); ++i) differ += same->T[i] != ref->T[i];
  EXPECT_EQ(differ, 0);
  if (!other) return;
  // other ranks: to round-off
  double accounts = 0, temps = 0;
  for (const char* a : kAccounts) {
    const double r = h[a].get<double>(), o = other->heat[a].get<double>();
    accounts = std::max(accounts, r == o ? 0.0 : std::fabs(o - r) / std::fabs(r));
  }
  for (std::size_t i = 0; i < ref->T.size(); ++i)
    if (ref->T[i] != 0) temps = std::max(temps, std::fabs(other->T[i] - ref->T[i]) / ref->T[i]);
  std::printf(
      "restart on %d ranks against the run on %d: accounts %.2e, temperatures %.2e "
      "relative; balance %.2e\n",
      world.size(), W, accounts, temps, other->heat["energy_balance"].get<double>());
  EXPECT_LE(accounts, 1e-12);
  EXPECT_LE(temps, 1e-12);
  EXPECT_LE(other->heat["energy_balance"].get<double>(), 1e-12);
}

}  // namespace
