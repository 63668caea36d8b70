// The collective error path and the small MPI module.
#include <gtest/gtest.h>

#include "coloc/core/comm.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/timers.hpp"

TEST(Comm, RaiseIfAnyThrowsOnEveryRankWithTheFirstMessage) {
  const auto comm = coloc::Comm::world();
  const int last = comm.size() - 1;
  std::string local = comm.rank() == last ? "particle 17 left the box" : "";
  try {
    comm.raiseIfAny(local);
    FAIL() << "no exception";
  } catch (const coloc::Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("particle 17 left the box"), std::string::npos) << what;
    if (comm.size() > 1) {
      EXPECT_NE(what.find("rank " + std::to_string(last)), std::string::npos);
    }
  }
  EXPECT_NO_THROW(comm.raiseIfAny(""));
}

TEST(Comm, ReductionsAndBroadcast) {
  const auto comm = coloc::Comm::world();
  const int n = comm.size();
  EXPECT_EQ(comm.sum(comm.rank() + 1), n * (n + 1) / 2);
  const auto m = comm.minMaxAvg(static_cast<double>(comm.rank()));
  EXPECT_EQ(m.min, 0.0);
  EXPECT_EQ(m.max, n - 1.0);
  EXPECT_DOUBLE_EQ(m.avg, (n - 1) / 2.0);
  EXPECT_EQ(comm.broadcast(comm.isRoot() ? std::string("hello") : std::string()), "hello");
}

TEST(Timers, ReportHasEveryTimedPhaseAndTheExchangeKinds) {
  const auto comm = coloc::Comm::world();
  coloc::Timers t;
  t.start(coloc::Phase::DemForce);
  t.stop(coloc::Phase::DemForce);
  t.book(coloc::Exchange::InterPhysicsRemote, 100, 2, 0.5);
  const auto j = t.report(comm, 1.0);
  EXPECT_EQ(j["timers"]["dem_force"]["calls"].get<long long>(), 1);
  EXPECT_FALSE(j["timers"].contains("fluid_momentum"));
  EXPECT_EQ(j["exchange"]["inter_physics_remote"]["bytes"].get<long long>(), 100LL * comm.size());
  EXPECT_EQ(j["exchange"]["intra_physics"]["messages"].get<long long>(), 0);
  EXPECT_TRUE(j["fractions"].contains("inter_physics"));
  EXPECT_GT(coloc::peakRssBytes(), 0);
}

TEST(Timers, NestedStartsOfOnePhaseCountOnce) {
  coloc::Timers t;
  t.start(coloc::Phase::Setup);
  t.start(coloc::Phase::Setup);  // e.g. a solver timing its own set-up inside the driver's
  const double t0 = MPI_Wtime();
  while (MPI_Wtime() - t0 < 0.01) {
  }
  t.stop(coloc::Phase::Setup);
  t.stop(coloc::Phase::Setup);
  EXPECT_EQ(t.calls(coloc::Phase::Setup), 1);
  EXPECT_LT(t.seconds(coloc::Phase::Setup), 0.015 + 0.5);
  EXPECT_GE(t.seconds(coloc::Phase::Setup), 0.01);
}

namespace {
void spin(double seconds) {
  const double t0 = MPI_Wtime();
  while (MPI_Wtime() - t0 < seconds) {
  }
}
}  // namespace

TEST(Timers, APhaseInsideAnotherPausesIt) {
  // Exclusive nesting: every moment belongs to one phase, so the phases add up to the wall time.
  coloc::Timers t;
  const double t0 = MPI_Wtime();
  t.start(coloc::Phase::ExchangeRemote);
  spin(0.01);
  t.start(coloc::Phase::CouplingDeposit);
  spin(0.03);
  t.stop(coloc::Phase::CouplingDeposit);
  spin(0.01);
  t.stop(coloc::Phase::ExchangeRemote);
  const double total = MPI_Wtime() - t0;
  const double outer = t.seconds(coloc::Phase::ExchangeRemote);
  const double inner = t.seconds(coloc::Phase::CouplingDeposit);
  EXPECT_GE(inner, 0.03);
  EXPECT_GE(outer, 0.02);
  // The inner 30 ms are not booked twice: the two phases are disjoint intervals inside
  // [t0, end], so their sum cannot exceed the wall time (booked to both, it would exceed it by
  // the inner 30 ms). A preemption between clock reads only makes the sum smaller.
  EXPECT_LE(outer + inner, total);
  EXPECT_EQ(t.calls(coloc::Phase::ExchangeRemote), 1);
  EXPECT_EQ(t.calls(coloc::Phase::CouplingDeposit), 1);
}
