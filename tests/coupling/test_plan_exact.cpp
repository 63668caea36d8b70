// `coloc plan` is exact: for every strategy (tiled included), the bytes and messages it predicts
// for each rank and each kind of traffic (coupling/plan.hpp) equal what the first step of a real
// run books in the exchange ledger (Timers, by Traffic kind), rank by rank. Run at 2, 3, 4, 8 and
// 16 ranks (oversubscribed: counts do not depend on timing). Tiny grids so that 16 ranks stay fast.
#include <gtest/gtest.h>

#include <string>

#include "coloc/coupling/plan.hpp"
#include "coloc/coupling/simulation.hpp"
#include "coupled_util.hpp"

using namespace coloc;

namespace {

// A layered bed in a closed box, gas from below (coupled, DEM ghosts every sub-step).
const char* const kBed = test::kLayeredBedCase;

// Suspended particles in a channel periodic along y and z (DummyDEM: the particles are frozen).
const char* kChannel = R"({
  "domain": { "length": [0.32, 0.08, 0.08], "cells": [16, 8, 8],
              "periodic": { "y": true, "z": true } },
  "run": { "mode": "dummy_dem", "steps": 1 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 1e-4, "initial_velocity": [0.05, 0.0, 0.0],
             "boundary": { "xlo": { "type": "inlet", "velocity": [0.05, 0.0, 0.0] },
                           "xhi": { "type": "outlet", "pressure": 0.0 } } },
  "particles": {
    "dt": 1e-4,
    "materials": [ { "density": 1000.0, "young": 1e5, "poisson": 0.3 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.0], "hi": [0.32, 0.08, 0.08],
                   "count": 1200, "radius": 0.002, "velocity_spread": 0.0 } ]
  },
  "coupling": { "dem_substeps": 1 }
})";

// Periodic along x, coupled: DEM ghosts cross the periodic face with a shift.
const char* const kPeriodic = test::kPeriodicSuspensionCase;

// The layered bed heated (fluid energy, particle temperature, Gunn convection): the temperature
// column of the DEM's ghost update, the fluid's T halo, the two deposited heat fields and the
// proxy rows' heat columns.
const char* kHeatedBed = R"({
  "domain": { "length": [0.16, 0.04, 0.16], "cells": [16, 4, 16] },
  "gravity": [0.0, 0.0, -9.81],
  "run": { "mode": "coupled", "steps": 1 },
  "fluid": { "nu": 1.5e-5, "rho": 1.2, "dt": 5e-4,
             "heat": true, "conductivity": 0.026, "heat_capacity": 1006.0,
             "initial_temperature": 300.0,
             "boundary": { "zlo": { "type": "inlet", "velocity": [0.0, 0.0, 0.3], "superficial": true,
                                    "temperature": 400.0 },
                           "zhi": { "type": "outlet", "pressure": 0.0 } } },
  "particles": {
    "dt": 5e-5, "heat": true,
    "materials": [ { "density": 2500.0, "young": 1e6, "poisson": 0.3,
                     "heat_capacity": 840.0, "conductivity": 1.0 } ],
    "sources": [ { "type": "layered", "lo": [0.0, 0.0, 0.0], "hi": [0.16, 0.04, 0.05],
                   "count": 1500, "radius": 0.002 } ]
  },
  "coupling": { "heat_transfer": "gunn" }
})";

// The channel heated, particles frozen (run.mode dummy_dem): a frozen sub-step with particles.heat
// refreshes the ghosts' temperatures (the DEM's ghost update, every sub-step), Gunn convection.
const char* kHeatedChannel = R"({
  "domain": { "length": [0.32, 0.08, 0.08], "cells": [16, 8, 8],
              "periodic": { "y": true, "z": true } },
  "run": { "mode": "dummy_dem", "steps": 1 },
  "fluid": { "nu": 1e-6, "rho": 1000.0, "dt": 2e-4, "initial_velocity": [0.05, 0.0, 0.0],
             "heat": true, "conductivity": 0.6, "heat_capacity": 4180.0,
             "initial_temperature": 300.0,
             "boundary": { "xlo": { "type": "inlet", "velocity": [0.05, 0.0, 0.0],
                                    "temperature": 350.0 },
                           "xhi": { "type": "outlet", "pressure": 0.0 } } },
  "particles": {
    "dt": 1e-4, "heat": true,
    "materials": [ { "density": 1000.0, "young": 1e5, "poisson": 0.3,
                     "heat_capacity": 840.0, "conductivity": 1.0 } ],
    "sources": [ { "type": "random", "lo": [0.0, 0.0, 0.0], "hi": [0.32, 0.08, 0.08],
                   "count": 1200, "radius": 0.002, "velocity_spread": 0.0 } ]
  },
  "coupling": { "heat_transfer": "gunn" }
})";

struct Param {
  const char* name;
  const char* text;
  const char* strategy;
};

class PlanExact : public ::testing::TestWithParam<Param> {};

}  // namespace

TEST_P(PlanExact, FirstStepLedgerEqualsPlanPerRankAndKind) {
  const Param& P = GetParam();
  const Comm world = Comm::world();
  const Config cfg = test::caseFromText(P.text, {std::string("partition.strategy=") + P.strategy});
  coupling::Simulation sim(world, cfg);
  sim.beginRun();
  sim.step();
  ASSERT_EQ(sim.particles()->rebuildCount(), 0) << "the case must not rebuild in its first step";

  const coupling::PlanCase pc = coupling::planCase(cfg);
  const coupling::LayoutPlan plan = coupling::planLayout(pc, P.strategy, world.size());
  ASSERT_TRUE(plan.error.empty()) << plan.error;
  const auto& dec = sim.decomposition();
  if (dec.isTiled()) {  // the same boxes
    ASSERT_EQ(plan.boxes.size(), static_cast<std::size_t>(world.size()));
    for (int r = 0; r < world.size(); ++r) {
      EXPECT_EQ(plan.boxes[static_cast<std::size_t>(r)].lo, dec.loOf(r));
      EXPECT_EQ(plan.boxes[static_cast<std::size_t>(r)].hi, dec.hiOf(r));
    }
  } else {
    EXPECT_EQ(plan.fluid.dims, dec.dims());
    EXPECT_EQ(plan.fluid.cuts, dec.cuts());
    EXPECT_EQ(plan.particles.cuts, sim.particleDecomposition().cuts());
  }
  const int me = dec.rank();
  ASSERT_EQ(me, sim.particleDecomposition().rank());
  const auto& R = plan.rank[static_cast<std::size_t>(me)];
  EXPECT_EQ(R.cells, dec.ownedCellCount());
  EXPECT_EQ(R.particles, static_cast<long long>(sim.particles()->particles().nOwned));
  EXPECT_EQ(R.demGhosts, static_cast<long long>(sim.particles()->particles().nGhost));
  long long any = 0;
  for (std::size_t t = 0; t < coupling::kTrafficKinds; ++t) {
    const auto kind = static_cast<Traffic>(t);
    EXPECT_EQ(R.perStep[t].bytes, sim.timers().bytes(kind))
        << P.name << " " << P.strategy << " rank " << me << ": " << kTrafficNames[t] << " bytes";
    EXPECT_EQ(R.perStep[t].messages, sim.timers().messages(kind))
        << P.name << " " << P.strategy << " rank " << me << ": " << kTrafficNames[t] << " messages";
    any += R.perStep[t].bytes;
  }
  // Non-trivial: on more than one rank something moves between ranks in every case.
  EXPECT_GT(world.sum(any), 0);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, PlanExact,
    ::testing::Values(
        Param{"bed", kBed, "uniform"}, Param{"bed", kBed, "balanced"},
        Param{"bed", kBed, "independent"}, Param{"channel", kChannel, "uniform"},
        Param{"channel", kChannel, "balanced"}, Param{"channel", kChannel, "independent"},
        Param{"periodic", kPeriodic, "uniform"}, Param{"periodic", kPeriodic, "balanced"},
        Param{"periodic", kPeriodic, "independent"}, Param{"bed", kBed, "tiled"},
        Param{"channel", kChannel, "tiled"}, Param{"periodic", kPeriodic, "tiled"},
        Param{"heated", kHeatedBed, "uniform"}, Param{"heated", kHeatedBed, "independent"},
        Param{"heated", kHeatedBed, "tiled"}, Param{"heated_frozen", kHeatedChannel, "uniform"},
        Param{"heated_frozen", kHeatedChannel, "independent"},
        Param{"heated_frozen", kHeatedChannel, "tiled"}),
    [](const auto& info) { return std::string(info.param.name) + "_" + info.param.strategy; });
