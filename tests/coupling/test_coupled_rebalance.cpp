// Re-balancing during a run (partition.rebalance_interval): a balanced (or tiled) run that starts
// on even blocks with its particles in the lower part of the box moves onto new cuts (boxes),
// carrying cells, particles and contact histories together. Checked against a serial run of the
// same case: every particle's position and velocity equal to 1e-10 relative at the end; across the
// move, the particle set, the fluid fields (sums over the cells) and every contact history (by pair
// of global ids) are unchanged; the new blocks lower the modelled imbalance.
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "coloc/coupling/rebalance.hpp"
#include "coloc/partition/setup.hpp"
#include "coloc/partition/tiled.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

constexpr int kCount = 800;

// A bed settling in the lower quarter of a tall closed box with an outlet on top (even blocks
// cut it along z: the upper blocks have no particles).
// The cuts from the case's weights (partition.rebalance_weights = case): the measured ones move
// with the machine's load, and with them the blocks and the order of the cross-block sums, so
// that a run would meet other layouts than the one before it.
const std::string kCase = test::settlingBedCase(
    kCount, 30,
    R"("rebalance_interval": 10, "rebalance_threshold": 1.02, "rebalance_weights": "case")");

/// Every particle's position and velocity by global id, on every rank.
std::vector<double> trajectories(coupling::Simulation& sim) {
  std::vector<double> s(6 * kCount, 0.0);
  const auto& p = sim.particles()->particles();
  for (std::size_t i = 0; i < p.nOwned; ++i)
    for (int d = 0; d < 3; ++d) {
      s[6 * static_cast<std::size_t>(p.id[i]) + static_cast<std::size_t>(d)] = p.x[d][i];
      s[6 * static_cast<std::size_t>(p.id[i]) + 3 + static_cast<std::size_t>(d)] = p.v[d][i];
    }
  sim.decomposition().comm().sumInPlace(std::span<double>(s));
  return s;
}

/// |tangential history| of every touching pair (a, b), a < b, then of every particle-wall
/// contact (holder, wall: partner -1 - wall), on every rank (a pair split across blocks is held
/// by both sides: the larger of the two, equal to round-off).
constexpr int kWalls = 6;
std::vector<double> histories(coupling::Simulation& sim) {
  std::vector<double> h(kCount * kCount + kCount * kWalls, 0.0);
  const dem::DemState s = sim.particles()->saveState();
  for (const auto& c : s.contacts) {
    const double n =
        std::sqrt(c.shear[0] * c.shear[0] + c.shear[1] * c.shear[1] + c.shear[2] * c.shear[2]);
    std::int64_t slot = -1;
    if (c.partner < 0 && c.partner >= -kWalls && c.holder >= 0 && c.holder < kCount)
      slot = kCount * kCount + c.holder * kWalls + (-1 - c.partner);
    else if (c.partner >= 0) {
      const auto a = std::min(c.holder, c.partner), b = std::max(c.holder, c.partner);
      if (a >= 0 && b < kCount) slot = a * kCount + b;
    }
    if (slot < 0) {
      ADD_FAILURE() << "contact history of holder " << c.holder << ", partner " << c.partner
                    << ": not a particle id or a wall";
      continue;
    }
    double& v = h[static_cast<std::size_t>(slot)];
    v = std::max(v, n);
  }
  sim.decomposition().comm().maxInPlace(std::span<double>(h));
  return h;
}

/// Sums of eps, p and the face velocities over the owned cells, and the cell count (global).
std::array<double, 4> fieldSums(coupling::Simulation& sim) {
  std::array<double, 4> s{};
  const auto& f = sim.fluid()->fields();
  forEach(f.p.interior(), [&](int i, int j, int k) {
    s[0] += f.eps(i, j, k);
    s[1] += f.p(i, j, k);
    s[2] += std::abs(f.u[2](i, j, k));
    s[3] += 1.0;
  });
  sim.decomposition().comm().sumInPlace(std::span<double>(s));
  return s;
}

/// Every rank's box, to tell whether a move changed the layout.
std::vector<Int3> boxesOf(const Decomposition& dec) {
  std::vector<Int3> lo, hi;
  dec.boxes(lo, hi);
  lo.insert(lo.end(), hi.begin(), hi.end());
  return lo;
}

class Rebalance : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(Rebalance, MovesCellsParticlesAndHistoriesTogether) {
  const Comm world = Comm::world();
  const test::SelfComm selfComm;
  {
    const std::string strategy = GetParam();
    const Config cfg = test::caseFromText(kCase, {"partition.strategy=" + strategy});
    const Config serialCfg = test::caseFromText(kCase, {"partition.rebalance_interval=0"});
    const std::string scratch =
        world.broadcast((std::filesystem::temp_directory_path() /
                         ("coloc_rebalance_" + std::to_string(::getpid()) + ".h5"))
                            .string());
    // Start on even blocks although most of the box is empty of particles.
    // (tiled: the even blocks as boxes).
    Decomposition evenBlocks = decompositionFromConfig(world, cfg);
    if (strategy == "tiled") evenBlocks = decompositionOf(world, boxLayoutOf(evenBlocks));
    coupling::Layouts even{std::move(evenBlocks), std::nullopt, strategy, CostModel{}, 1.0, 1.0};
    auto sim = std::make_unique<coupling::Simulation>(cfg, std::move(even));
    coupling::Simulation ser(selfComm.comm(), serialCfg);
    int moves = 0;
    while (!sim->finished()) {
      sim->step();
      ser.step();
      if (!coupling::rebalanceDue(cfg, sim->steps())) continue;
      const auto plan = coupling::planRebalance(*sim, cfg);
      if (!plan.layouts) continue;
      EXPECT_GT(plan.gain, 1.02);
      EXPECT_LT(plan.newImbalance, plan.currentImbalance);
      const auto before = trajectories(*sim);
      const auto hBefore = histories(*sim);
      const auto fBefore = fieldSums(*sim);
      const long long steps = sim->steps();
      const double time = sim->time();
      const auto oldBoxes = boxesOf(sim->decomposition());
      sim = coupling::applyRebalance(std::move(sim), cfg, *plan.layouts, scratch);
      ++moves;
      EXPECT_NE(boxesOf(sim->decomposition()), oldBoxes);
      EXPECT_EQ(sim->decomposition().isTiled(), strategy == "tiled");
      EXPECT_EQ(sim->steps(), steps);
      EXPECT_EQ(sim->time(), time);
      EXPECT_EQ(sim->particles()->globalCount(), kCount);
      EXPECT_EQ(trajectories(*sim), before);  // the state moves bit for bit
      const auto fAfter = fieldSums(*sim);
      EXPECT_EQ(fAfter[3], fBefore[3]);
      for (int q = 0; q < 3; ++q)
        EXPECT_NEAR(fAfter[q], fBefore[q], 1e-12 * std::max(1.0, std::abs(fBefore[q])));
      const auto hAfter = histories(*sim);
      double hmax = 0;
      int pairs = 0;
      for (double v : hBefore) hmax = std::max(hmax, v);
      for (std::size_t k = 0; k < hBefore.size(); ++k) {
        pairs += k < static_cast<std::size_t>(kCount) * kCount && hBefore[k] > 0;
        ASSERT_EQ(hBefore[k] > 0, hAfter[k] > 0) << "pair " << k / kCount << "-" << k % kCount;
        ASSERT_NEAR(hBefore[k], hAfter[k], 1e-12 * hmax);
      }
      EXPECT_GT(pairs, 0);  // the bed has sliding contacts to carry
      if (world.isRoot())
        std::printf("re-balanced at step %lld: modelled imbalance %.3f -> %.3f, %d sliding pairs\n",
                    steps, plan.currentImbalance, plan.newImbalance, pairs);
    }
    if (world.size() > 1) {
      EXPECT_GE(moves, 1);
    }
    EXPECT_FALSE(std::filesystem::exists(scratch));
    const auto a = trajectories(*sim), b = trajectories(ser);
    double vmax = 0;
    for (std::size_t k = 0; k < b.size(); k += 6)
      for (int d = 3; d < 6; ++d) vmax = std::max(vmax, std::abs(b[k + d]));
    ASSERT_GT(vmax, 0.0);
    for (std::size_t k = 0; k < a.size(); ++k)
      ASSERT_NEAR(a[k], b[k], 1e-10 * (k % 6 < 3 ? 0.12 : vmax)) << "particle " << k / 6;
  }
}

INSTANTIATE_TEST_SUITE_P(Strategies, Rebalance, ::testing::Values("balanced", "tiled"));
