// Start-up checks and collective errors (issue 4): each must stop every rank with a message
// naming the cause, with no hang. Also DummyDEM (setFrozen) and the time-step limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "dem_test_util.hpp"

namespace {

std::string caseText(
    const std::string& particles,
    const std::string& domain = R"("length": [0.1, 0.1, 0.1], "cells": [10, 10, 10])") {
  return "{\"domain\": {" + domain + "}, \"particles\": {" + particles + "}}";
}

const std::string kMat =
    R"("materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.9}])";

/// Message of the coloc::Error thrown when building and running `steps` steps ("" if none).
template <class E = coloc::Error>
std::string failure(const std::string& text, int steps = 0) {
  try {
    demtest::Case c(text);
    for (int s = 0; s < steps; ++s) c.dem->substep();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

TEST(DemSetup, BinSmallerThanInteractionRange) {
  // cells of 5 mm, particles of 4 mm diameter: range 4.8 mm; a bin of 1/2 cell is too small
  const auto msg = failure<coloc::ConfigError>(
      caseText(kMat + R"(, "dt": 1e-6, "bin_split": 2, "sources": [{"type": "list",
      "positions": [0.05, 0.05, 0.05], "radius": 0.002}])",
               R"("length": [0.1, 0.1, 0.1], "cells": [20, 20, 20])"));
  EXPECT_NE(msg.find("particles.bin_split"), std::string::npos) << msg;
  EXPECT_NE(msg.find("smaller than the interaction range"), std::string::npos) << msg;
}

TEST(DemSetup, BinNotMatchingBlocks) {
  // 10 cells per axis cannot be cut into bins of 3 cells
  const auto msg = failure<coloc::ConfigError>(
      caseText(kMat + R"(, "dt": 1e-6, "bin_cells": 3, "sources": [{"type": "list",
      "positions": [0.05, 0.05, 0.05], "radius": 0.002}])"));
  EXPECT_NE(msg.find("particles.bin_cells"), std::string::npos) << msg;
  EXPECT_NE(msg.find("block edge"), std::string::npos) << msg;
}

TEST(DemSetup, AutomaticBinsCoincideWithCells) {
  // cells of 1 mm, range 2.4 mm: bins of 3 cells (the smallest multiple >= range)
  demtest::Case c(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.006, 0.006, 0.006], "radius": 0.001}])",
                           R"("length": [0.012, 0.012, 0.012], "cells": [12, 12, 12])"));
  EXPECT_DOUBLE_EQ(c.dem->binSize()[0], 0.003);
  EXPECT_DOUBLE_EQ(c.dem->interactionRange(), 0.0024);
}

TEST(DemSetup, TimeStepAboveRayleighLimit) {
  const auto msg = failure<coloc::ConfigError>(
      caseText(kMat + R"(, "dt": 1e-3, "sources": [{"type": "list", "positions": [0.05, 0.05, 0.05],
      "radius": 0.002}])"));
  EXPECT_NE(msg.find("particles.dt"), std::string::npos) << msg;
  EXPECT_NE(msg.find("Rayleigh time"), std::string::npos) << msg;
  EXPECT_NE(msg.find("use at most"), std::string::npos) << msg;
}

TEST(DemSetup, ParticleLeavingTheBoxStopsEveryRank) {
  // walls off: a fast particle crosses the high x face; only its owner sees it
  const auto msg =
      failure(caseText(kMat + R"(, "dt": 1e-5, "walls": false, "sources": [{"type": "list",
      "positions": [0.09, 0.02, 0.02, 0.02, 0.02, 0.02], "radius": 0.002,
      "velocities": [50, 0, 0, 0, 0, 0]}])"),
              100);
  EXPECT_NE(msg.find("left the box"), std::string::npos) << msg;
}

TEST(DemSetup, OverlapBeyondLimitStopsEveryRank) {
  const auto msg = failure(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.08, 0.08, 0.08, 0.0828, 0.08, 0.08], "radius": 0.002}])"));
  EXPECT_NE(msg.find("overlaps particle"), std::string::npos) << msg;
  EXPECT_NE(msg.find("overlap_limit"), std::string::npos) << msg;
}

TEST(DemSetup, SourceErrors) {
  auto msg = failure<coloc::ConfigError>(caseText(kMat + R"(, "sources": [{"type": "random",
      "lo": [0, 0, 0], "hi": [0.01, 0.01, 0.01], "count": 1000, "radius": 0.001}])"));
  EXPECT_NE(msg.find("particles.sources[0].count"), std::string::npos) << msg;
  msg = failure<coloc::ConfigError>(caseText(kMat + R"(, "sources": [{"type": "list",
      "positions": [0.05, 0.05, 0.05], "radius": 0.001, "material": 3}])"));
  EXPECT_NE(msg.find("particles.sources[0].material"), std::string::npos) << msg;
  msg = failure<coloc::ConfigError>(caseText(kMat + R"(, "sources": [{"type": "list",
      "positions": [0.05, 0.05, 0.15], "radius": 0.001}])"));
  EXPECT_NE(msg.find("outside the box"), std::string::npos) << msg;
}

/// Message of dem::checkCase on the case (no solver; "" if it passes).
std::string checkFailure(const std::string& text) {
  const coloc::Config cfg = demtest::config(text);
  const coloc::GlobalGrid g = coloc::gridFromConfig(cfg);
  try {
    coloc::dem::checkCase(cfg, g, coloc::dem::caseParticles(cfg, g, /*rows=*/true));
  } catch (const coloc::Error& e) {
    return e.what();
  }
  return "";
}

TEST(DemSetup, CaseChecksWithoutSolverRejectWhatConstructionRejects) {
  // `coloc check` runs dem::checkCase: every case a DemSolver's construction refuses with a
  // ConfigError, it refuses with the same message; valid cases pass.
  const std::string twoMats =
      R"("materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.9},
                       {"density": 900, "young": 1e6, "poisson": 0.4, "restitution": 0.9}])";
  const std::vector<std::string> refused = {
      caseText(kMat + R"(, "dt": 1e-3, "sources": [{"type": "list",
          "positions": [0.05, 0.05, 0.05], "radius": 0.002}])"),
      // the limit from the smaller particle of the softer material, not the smallest overall
      caseText(twoMats + R"(, "dt": 2.4e-5, "sources": [{"type": "list",
          "positions": [0.03, 0.05, 0.05], "radius": 0.001}, {"type": "list",
          "positions": [0.07, 0.05, 0.05], "radius": 0.002, "material": 1}])"),
      caseText(kMat + R"(, "dt": 1e-6, "bin_cells": 3, "sources": [{"type": "list",
          "positions": [0.05, 0.05, 0.05], "radius": 0.002}])"),
      caseText(kMat + R"(, "dt": 1e-6, "wall_material": 2, "sources": [{"type": "list",
          "positions": [0.05, 0.05, 0.05], "radius": 0.002}])"),
      caseText(kMat + R"(, "dt": 1e-6, "boundary": {"xlo": "periodic"}, "sources": [{"type":
          "list", "positions": [0.05, 0.05, 0.05], "radius": 0.002}])"),
      caseText(kMat + R"(, "sources": [{"type": "list", "positions": [0.05, 0.05, 0.15],
          "radius": 0.001}])")};
  for (const auto& text : refused) {
    const std::string run = failure<coloc::ConfigError>(text);
    ASSERT_FALSE(run.empty()) << text;
    EXPECT_EQ(checkFailure(text), run) << text;
  }
  const std::string ok = caseText(twoMats + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.09, 0.09, 0.09], "radius": 0.001}, {"type": "lattice", "lo": [0.01, 0.01,
      0.01], "spacing": [0.01, 0.01, 0.01], "counts": [8, 8, 8], "radius": 0.002,
      "material": 1}])");
  EXPECT_EQ(failure(ok), "");
  EXPECT_EQ(checkFailure(ok), "");
}

TEST(DemSetup, CaseChecksWithoutSolverFindInitialOverlaps) {
  // particles that overlap each other, a wall, or each other across a periodic face
  const auto pair = checkFailure(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.08, 0.08, 0.08, 0.0828, 0.08, 0.08], "radius": 0.002}])"));
  EXPECT_NE(pair.find("particle 0 overlaps particle 1 by 0.6"), std::string::npos) << pair;
  EXPECT_NE(pair.find("overlap_limit"), std::string::npos) << pair;
  const auto wall = checkFailure(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.0005, 0.05, 0.05], "radius": 0.002}])"));
  EXPECT_NE(wall.find("particle 0 overlaps a wall"), std::string::npos) << wall;
  const std::string periodic = R"("length": [0.1, 0.1, 0.1], "cells": [10, 10, 10],
      "periodic": {"x": true})";
  const auto across = checkFailure(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.0005, 0.05, 0.05, 0.0985, 0.05, 0.05], "radius": 0.002}])",
                                            periodic));
  EXPECT_NE(across.find("particle 0 overlaps particle 1"), std::string::npos) << across;
  EXPECT_FALSE(failure(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.0005, 0.05, 0.05, 0.0985, 0.05, 0.05], "radius": 0.002}])",
                                periodic))
                   .empty());
  // touching is not overlapping beyond the limit
  EXPECT_EQ(checkFailure(caseText(kMat + R"(, "dt": 1e-6, "sources": [{"type": "list",
      "positions": [0.05, 0.05, 0.05, 0.054, 0.05, 0.05], "radius": 0.002}])")),
            "");
}

TEST(DemSetup, FrozenParticlesDoNotMove) {
  demtest::Case c(
      "{\"gravity\": [0, 0, -9.81], \"domain\": {\"length\": [0.1, 0.1, 0.1], "
      "\"cells\": [10, 10, 10]}, \"particles\": {" +
      kMat +
      R"(, "dt": 1e-6, "sources": [{"type": "lattice", "lo": [0.01, 0.01, 0.01],
                  "counts": [5, 5, 5], "spacing": [0.005, 0.005, 0.005], "radius": 0.002,
                  "velocity": [1, 0, 0]}]}})");
  c.dem->setFrozen(true);
  auto& p = c.p();
  for (std::size_t i = 0; i < p.nOwned; ++i) p.fExt[2][i] = 1.0;
  const auto before = demtest::table(c, 125);
  for (int s = 0; s < 50; ++s) c.dem->substep();
  const auto after = demtest::table(c, 125);
  EXPECT_EQ(before, after);
  EXPECT_DOUBLE_EQ(c.dem->time(), 50 * 1e-6);
  EXPECT_EQ(c.dem->globalCount(), 125);
}

}  // namespace

// report.json's particles.bytes_by_part: the names researchers plot (stable across refactors:
// they name what the storage holds, not which class owns it), and the parts add up to
// particles.bytes_per_particle.
TEST(DemMemory, PartsKeepTheirNamesAndAddUp) {
  demtest::Case c(caseText(
      kMat +
      R"(, "dt": 1e-5, "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.1, 0.1, 0.05],
          "count": 400, "radius": 0.002}])"));
  for (int s = 0; s < 5; ++s) c.dem->substep();
  const auto d = c.dem->diagnostics();
  ASSERT_TRUE(d.contains("bytes_by_part"));
  std::vector<std::string> names;
  double sum = 0;
  for (const auto& [k, v] : d["bytes_by_part"].items()) {
    names.push_back(k);
    sum += v.get<double>();
  }
  for (const char* want :
       {"field.x", "field.v", "bins", "list.rows", "list.nbr", "list.slot", "hist.rows",
        "hist.key_x0", "hist.shear", "hist.free", "ghosts", "scratch", "body"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
  for (const auto& n : names)
    EXPECT_TRUE(n.rfind("field.", 0) == 0 || n.find('.') == n.rfind('.')) << n;
  EXPECT_NEAR(sum, d["bytes_per_particle"].get<double>(),
              1e-9 * d["bytes_per_particle"].get<double>());
}
