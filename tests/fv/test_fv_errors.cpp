// Bad fluid input and run-time failures: every rank gets the same coloc::Error naming the key,
// or the step, the cell and the value (no hang).
#include <gtest/gtest.h>

#include "fv_test_util.hpp"

using namespace coloc;

namespace {
std::string errorOf(const std::string& text, const std::vector<std::string>& ov = {}) {
  try {
    const Config cfg = fvtest::config(text, ov);
    const Decomposition dec = decompositionFromConfig(Comm::world(), cfg);
    Timers timers;
    fv::FluidSolver s(dec, cfg, timers);
    for (int n = 0; n < 50; ++n) s.step(s.nextDt());
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const char* kBox = R"({"domain": {"length": [1, 1, 1], "cells": [8, 6, 4], "periodic": {"z": true}},
                       "fluid": {"nu": 0.01}})";
}  // namespace

TEST(FvErrors, PeriodicMismatchNamesTheKey) {
  const std::string e =
      errorOf(kBox, {R"(fluid.boundary.zlo={"type":"inlet","velocity":[0,0,1]})"});
  EXPECT_NE(e.find("fluid.boundary.zlo"), std::string::npos) << e;
  EXPECT_NE(e.find("domain.periodic.z"), std::string::npos) << e;
  const std::string e2 = errorOf(kBox, {R"(fluid.boundary.xhi={"type":"periodic"})"});
  EXPECT_NE(e2.find("fluid.boundary.xhi"), std::string::npos) << e2;
}

TEST(FvErrors, WallMustMoveTangentially) {
  const std::string e = errorOf(kBox, {R"(fluid.boundary.ylo={"type":"wall","velocity":[0,1,0]})"});
  EXPECT_NE(e.find("fluid.boundary.ylo.velocity"), std::string::npos) << e;
}

TEST(FvErrors, CflAboveHardLimitStopsWithStepCellValue) {
  // A 10 m/s inlet with a fixed dt = 0.1 s on h = 1/8 m: CFL ~ 8 at the first step (step 1).
  const std::string e = errorOf(kBox, {R"(fluid.boundary.xlo={"type":"inlet","velocity":[10,0,0]})",
                                       R"(fluid.boundary.xhi={"type":"outlet"})", "fluid.dt=0.1"});
  EXPECT_NE(e.find("fluid step 1:"), std::string::npos) << e;
  EXPECT_NE(e.find("CFL"), std::string::npos) << e;
  EXPECT_NE(e.find("at cell ("), std::string::npos) << e;
  EXPECT_NE(e.find("fluid.cfl_max"), std::string::npos) << e;
}

TEST(FvErrors, NonFiniteVelocityStops) {
  const std::string e =
      errorOf(kBox, {"fluid.body_force=[1e308, 0, 0]", "fluid.dt=1e10", "fluid.cfl_max=1e300"});
  EXPECT_NE(e.find("fluid step 1: non-finite velocity"), std::string::npos) << e;
  EXPECT_NE(e.find("at cell ("), std::string::npos) << e;
}

TEST(FvErrors, BadPatchesNameTheKey) {
  // On a periodic face.
  std::string e = errorOf(
      kBox, {R"(fluid.patches=[{"type":"outlet","face":"zhi","min":[0,0],"max":[0.5,0.5]}])"});
  EXPECT_NE(e.find("fluid.patches[0].face"), std::string::npos) << e;
  EXPECT_NE(e.find("periodic"), std::string::npos) << e;
  // Containing no cell face centre (xhi: y cells of 1/6, centres at 1/12, 3/12, ...).
  e = errorOf(kBox,
              {R"(fluid.patches=[{"type":"outlet","face":"xhi","min":[0.4,0.3],"max":[0.6,0.7]},
                                       {"type":"outlet","face":"xhi","min":[0.0,0.0],"max":[0.01,1]}])"});
  EXPECT_NE(e.find("fluid.patches[1]"), std::string::npos) << e;
  EXPECT_NE(e.find("no cell face centre"), std::string::npos) << e;
  // Three coordinates instead of two; max below min.
  e = errorOf(kBox,
              {R"(fluid.patches=[{"type":"outlet","face":"xlo","min":[0,0,0],"max":[1,1]}])"});
  EXPECT_NE(e.find("fluid.patches[0].min"), std::string::npos) << e;
  e = errorOf(kBox,
              {R"(fluid.patches=[{"type":"outlet","face":"ylo","min":[0.5,0],"max":[0.2,1]}])"});
  EXPECT_NE(e.find("fluid.patches[0].max"), std::string::npos) << e;
  // A wall patch that moves normally to its face.
  e = errorOf(kBox, {R"(fluid.patches=[{"type":"wall","face":"ylo","min":[0,0],"max":[1,1],
                                        "velocity":[0,1,0]}])"});
  EXPECT_NE(e.find("fluid.patches[0].velocity"), std::string::npos) << e;
}
