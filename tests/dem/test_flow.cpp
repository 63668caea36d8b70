// Particles leaving and entering (issue 18): outflow faces, inflow sources, size distributions.
//  - a bed falling out through an outflow floor, with contacts and friction: the run on 1, 2, 4
//    ranks equals a serial run (MPI_COMM_SELF) per id, the same particles are removed, and mass
//    initial = mass out + mass held;
//  - a conveying channel (inflow patch on xlo, outflow xhi, collisions): serial vs parallel per
//    id, the inflow count follows the rate, the count reaches a steady value, balance exact;
//  - an inflow into a closed box fills every insertion site exactly once, then waits;
//  - size distributions: cut-offs, the median of a truncated log-normal, discrete weights, the
//    bins sized by the largest diameter, the time-step check by the smallest inflow particle;
//  - start-up errors naming the key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "dem_test_util.hpp"

namespace {

using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

const char* kHopper = R"({
  "gravity": [0, 0, -9.81],
  "domain": {"length": [0.03, 0.03, 0.06], "cells": [6, 6, 12]},
  "particles": {
    "dt": 1e-5,
    "boundary": {"zlo": "outflow"},
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.5,
                   "friction": 0.5}],
    "sources": [{"type": "lattice", "lo": [0.0017, 0.0017, 0.003], "counts": [8, 8, 6],
                 "spacing": [0.0022, 0.0022, 0.0022], "jitter": 0.5,
                 "size": {"type": "uniform", "min": 0.0016, "max": 0.002},
                 "velocity": [0, 0, -0.3], "velocity_spread": 0.3}]
  }
})";

/// Largest |a - b| over the positions of ids present in both tables, and the number of ids
/// present in one table only.
void compare(const std::vector<double>& a, const std::vector<double>& b, long n, double* dx,
             long* mismatch) {
  *dx = 0;
  *mismatch = 0;
  for (long k = 0; k < n; ++k) {
    const auto q = static_cast<std::size_t>(10 * k);
    if (a[q] != b[q]) ++*mismatch;
    if (a[q] != 1.0 || b[q] != 1.0) continue;
    for (int d = 0; d < 6; ++d) *dx = std::max(*dx, std::fabs(a[q + 1 + d] - b[q + 1 + d]));
  }
}

TEST(DemFlow, OutflowFloorMatchesSerial) {
  const long n = 384;
  Case par(kHopper);
  Case ser(kHopper, kSelf, {1, 1, 1});
  double worst = 0, contacts = 0;
  long worstMismatch = 0;
  for (int s = 0; s < 2500; ++s) {
    par.dem->substep();
    ser.dem->substep();
    if (s % 250 == 249) {
      contacts = std::max(contacts, par.dem->diagnostics()["contacts_per_particle"].get<double>());
      double dx;
      long mm;
      compare(demtest::table(par, n), demtest::table(ser, n), n, &dx, &mm);
      worst = std::max(worst, dx);
      worstMismatch = std::max(worstMismatch, mm);
    }
  }
  const auto dp = par.dem->diagnostics(), ds = ser.dem->diagnostics();
  if (par.dec.comm().isRoot())
    std::printf(
        "outflow floor, ranks %d: %lld of %ld left through zlo, max |x, v - serial| %.3e, "
        "most contacts/particle %.3f, balance %.2e\n",
        par.dec.size(), dp["count_out"].get<long long>(), n, worst, contacts,
        dp["mass_balance"].get<double>());
  EXPECT_EQ(worstMismatch, 0);  // the same particles removed at the same steps
  EXPECT_LE(worst, 1e-10 * 0.06);
  EXPECT_EQ(dp["count_out"], ds["count_out"]);
  EXPECT_GT(dp["count_out"].get<long long>(), 50);  // a good part of the bed left
  EXPECT_LT(dp["count_out"].get<long long>(), n);
  EXPECT_EQ(dp["count_out_by_face"]["zlo"], dp["count_out"]);
  EXPECT_EQ(dp["count"].get<long long>() + dp["count_out"].get<long long>(), n);
  EXPECT_NEAR(dp["mass_out"].get<double>(), ds["mass_out"].get<double>(),
              1e-13 * ds["mass_out"].get<double>());
  EXPECT_LE(dp["mass_balance"].get<double>(), 1e-13);
  EXPECT_GT(contacts, 0.05);  // contacts (tens of touching pairs) with histories
}

using demtest::channel;

TEST(DemFlow, ConveyingChannelMatchesSerialAndReachesSteadyCount) {
  const std::string text = channel();
  Case par(text);
  Case ser(text, kSelf, {1, 1, 1});
  const long n = 2000;  // ids are below the particles due (rate x time)
  std::vector<long long> counts;
  double worst = 0;
  long worstMismatch = 0;
  for (int s = 0; s < 6000; ++s) {
    par.dem->substep();
    ser.dem->substep();
    if (s % 500 == 499) {
      counts.push_back(par.dem->globalCount());
      double dx;
      long mm;
      compare(demtest::table(par, n), demtest::table(ser, n), n, &dx, &mm);
      worst = std::max(worst, dx);
      worstMismatch = std::max(worstMismatch, mm);
    }
  }
  const auto dp = par.dem->diagnostics(), ds = ser.dem->diagnostics();
  if (par.dec.comm().isRoot()) {
    std::printf("channel, ranks %d: count every 500 steps:", par.dec.size());
    for (auto c : counts) std::printf(" %lld", c);
    std::printf("\n  in %lld, out %lld, waiting %lld, max |x, v - serial| %.3e, balance %.2e\n",
                dp["count_in"].get<long long>(), dp["count_out"].get<long long>(),
                dp["inflow_waiting"].get<long long>(), worst, dp["mass_balance"].get<double>());
  }
  EXPECT_EQ(worstMismatch, 0);
  EXPECT_LE(worst, 1e-10);
  EXPECT_EQ(dp["count_in"], ds["count_in"]);
  EXPECT_EQ(dp["count_out"], ds["count_out"]);
  EXPECT_EQ(dp["mass_in"].get<double>(), ds["mass_in"].get<double>());  // same sum everywhere
  // the rate is met: 20000/s over 0.06 s, minus what waits for a free site
  const long long due = 1199;  // floor(20000 * 5999e-5) at the start of the last step
  EXPECT_EQ(dp["count_in"].get<long long>() + dp["inflow_waiting"].get<long long>(), due);
  EXPECT_LE(dp["inflow_waiting"].get<long long>(), 3);
  EXPECT_GT(dp["count_out"].get<long long>(), 500);
  // steady: the last three samples within 10 % of their mean (transit ~0.02 s = 2000 steps)
  const double mean = (counts[9] + counts[10] + counts[11]) / 3.0;
  for (int k = 9; k < 12; ++k) EXPECT_NEAR(counts[static_cast<std::size_t>(k)], mean, 0.1 * mean);
  EXPECT_LE(dp["mass_balance"].get<double>(), 1e-13);
  EXPECT_GT(dp["contacts_per_particle"].get<double>() + 0.0, 0.0);
}

TEST(DemFlow, SaveAndRestoreContinueTheFlow) {
  // the channel saved after 1500 steps (particles waiting for a site included: a higher rate),
  // its flow tallies through the checkpoint's packing, restored on the same ranks: 1500 more
  // steps equal to the run that went on, tallies and particles
  std::string text = channel();
  text.replace(text.find("\"rate\": 20000"), 13, "\"rate\": 60000");
  Case a(text);
  for (int s = 0; s < 1500; ++s) a.dem->substep();
  coloc::dem::DemState st = a.dem->saveState();
  st.flow = coloc::dem::DemFlow::unpack(st.flow.pack());
  const long long waiting = a.dem->diagnostics()["inflow_waiting"].get<long long>();
  coloc::dem::DemSolver b(a.dec, a.cfg, a.timers, std::move(st));
  for (int s = 0; s < 1500; ++s) {
    a.dem->substep();
    b.substep();
  }
  const auto da = a.dem->diagnostics(), db = b.diagnostics();
  for (const char* k : {"count", "count_in", "count_out", "inflow_waiting"})
    EXPECT_EQ(da[k], db[k]) << k;
  EXPECT_EQ(da["mass_in"].get<double>(), db["mass_in"].get<double>());
  EXPECT_NEAR(da["mass_out"].get<double>(), db["mass_out"].get<double>(),
              1e-13 * da["mass_out"].get<double>());
  EXPECT_LE(db["mass_balance"].get<double>(), 1e-13);
  EXPECT_GT(waiting, 0);  // the waiting list travelled
  // particles: per id, bit for bit (the ids below count_in)
  const long n = static_cast<long>(da["count_in"].get<long long>());
  auto& pb = b.particles();
  std::vector<double> tb(static_cast<std::size_t>(10 * n), 0.0);
  for (std::size_t i = 0; i < pb.nOwned; ++i) {
    const auto k = static_cast<std::size_t>(10 * pb.id[i]);
    if (pb.id[i] >= n) continue;
    tb[k] += 1;
    for (int d = 0; d < 3; ++d) tb[k + 1 + d] = pb.x[d][i], tb[k + 4 + d] = pb.v[d][i];
  }
  a.dec.comm().sumInPlace(std::span<double>(tb));
  double dx;
  long mm;
  compare(demtest::table(a, n), tb, n, &dx, &mm);
  EXPECT_EQ(mm, 0);
  EXPECT_EQ(dx, 0.0);
}

TEST(DemFlow, InflowIntoAClosedBoxFillsEverySiteOnce) {
  // at rest, no gravity, no outflow: each of the 6 x 6 sites takes one particle, then the due
  // particles wait (a candidate on an occupied site always overlaps its occupant)
  const std::string text = R"({
  "domain": {"length": [0.03, 0.016, 0.016], "cells": [6, 4, 4]},
  "particles": {
    "dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3}],
    "inflow": [{"face": "xlo", "patch": {"min": [0.002, 0.002], "max": [0.014, 0.014]},
                "rate": 1e5, "radius": 0.001, "gap": 0.05}]
  }
})";
  Case c(text);
  for (int s = 0; s < 300; ++s) c.dem->substep();
  const auto d = c.dem->diagnostics();
  // site edge 2.1 mm: floor(12 / 2.1) = 5 sites per axis
  EXPECT_EQ(d["count"].get<long long>(), 25);
  EXPECT_EQ(d["count_in"].get<long long>(), 25);
  EXPECT_EQ(d["inflow_waiting"].get<long long>(), 299 - 25);
  EXPECT_LE(d["mass_balance"].get<double>(), 1e-14);
}

TEST(DemFlow, SizeDistributions) {
  // log-normal, median 1 mm, sigma 0.4, cut to [0.7, 2] mm, in a random packing (serial)
  const std::string text = R"({
  "domain": {"length": [0.06, 0.06, 0.06], "cells": [6, 6, 6]},
  "particles": {
    "dt": 1e-6,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3}],
    "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.06, 0.06, 0.04], "count": 4000,
                 "size": {"type": "lognormal", "median": 0.001, "sigma": 0.4, "min": 0.0007,
                          "max": 0.002}},
                {"type": "layered", "lo": [0, 0, 0], "hi": [0.06, 0.06, 0.03], "count": 0,
                 "radius": 0.0005},
                {"type": "lattice", "lo": [0.002, 0.002, 0.05], "counts": [14, 14, 1],
                 "spacing": [0.004, 0.004, 0.004],
                 "size": {"type": "discrete", "diameters": [0.001, 0.0015, 0.002],
                          "weights": [3, 0, 1]}}]
  }
})";
  Case c(text, kSelf, {1, 1, 1});
  auto& p = c.p();
  std::vector<double> d1;
  long small = 0, mid = 0, large = 0;
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    const double d = 2 * p.radius[i];
    if (p.id[i] < 4000) {
      d1.push_back(d);
    } else {
      if (std::fabs(d - 0.001) < 1e-12) ++small;
      if (std::fabs(d - 0.0015) < 1e-12) ++mid;
      if (std::fabs(d - 0.002) < 1e-12) ++large;
    }
  }
  ASSERT_EQ(d1.size(), 4000u);
  std::sort(d1.begin(), d1.end());
  EXPECT_GE(d1.front(), 0.0007);
  EXPECT_LE(d1.back(), 0.002);
  // median of the truncated distribution: F(m) = (F(a) + F(b)) / 2 with F the normal CDF of
  // ln(d / 1 mm) / 0.4
  const auto F = [](double d) {
    return 0.5 * std::erfc(-std::log(d / 0.001) / 0.4 / std::sqrt(2.0));
  };
  const double target = 0.5 * (F(0.0007) + F(0.002));
  double lo = 0.0007, hi = 0.002;
  for (int k = 0; k < 100; ++k) (F(0.5 * (lo + hi)) < target ? lo : hi) = 0.5 * (lo + hi);
  const double median = 0.5 * (d1[1999] + d1[2000]);
  std::printf(
      "log-normal: sample median %.5g mm, truncated median %.5g mm; discrete 1/1.5/2 mm: "
      "%ld %ld %ld\n",
      median * 1e3, lo * 1e3, small, mid, large);
  EXPECT_NEAR(median, lo, 0.03 * lo);  // 4000 samples: ~1 % standard error
  // discrete weights 3 : 0 : 1 over 196 particles: 147 expected small, sd ~6
  EXPECT_EQ(small + mid + large, 196);
  EXPECT_EQ(mid, 0);
  EXPECT_NEAR(static_cast<double>(small), 147.0, 25.0);
  // bins: the interaction range is the largest diameter + skin (0.2 of it)
  EXPECT_NEAR(c.dem->interactionRange(), 0.002 * 1.2, 1e-15);
}

template <class E>
std::string failure(const std::string& text) {
  try {
    Case c(text);
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

TEST(DemFlow, StartUpErrors) {
  const std::string mat = R"("materials": [{"density": 2500, "young": 1e7, "poisson": 0.3}])";
  const auto box = [&](const std::string& particles, const std::string& periodic = "") {
    return R"({"domain": {"length": [0.03, 0.016, 0.016], "cells": [6, 4, 4])" + periodic +
           R"(}, "particles": {"dt": 1e-6, )" + mat + ", " + particles + "}}";
  };
  auto msg = failure<coloc::ConfigError>(box(R"("boundary": {"xlo": "periodic"})"));
  EXPECT_NE(msg.find("particles.boundary.xlo"), std::string::npos) << msg;
  EXPECT_NE(msg.find("periodic fluid axis"), std::string::npos) << msg;
  msg = failure<coloc::ConfigError>(
      box(R"("boundary": {"ylo": "outflow"})", R"(, "periodic": {"y": true})"));
  EXPECT_NE(msg.find("particles.boundary.ylo"), std::string::npos) << msg;
  const std::string in = R"("inflow": [{"face": "xlo", "rate": 10, "radius": 0.001)";
  msg = failure<coloc::ConfigError>(box(R"("boundary": {"xlo": "outflow"}, )" + in + "}]"));
  EXPECT_NE(msg.find("particles.inflow[0].face"), std::string::npos) << msg;
  msg = failure<coloc::ConfigError>(box(in + R"(, "mass_rate": 1}])"));
  EXPECT_NE(msg.find("particles.inflow[0].rate"), std::string::npos) << msg;
  msg = failure<coloc::ConfigError>(
      box(in + R"(, "patch": {"min": [0.001, 0.001], "max": [0.002, 0.002]}}])"));
  EXPECT_NE(msg.find("narrower than one insertion site"), std::string::npos) << msg;
  msg = failure<coloc::ConfigError>(
      box(in + R"(, "size": {"type": "uniform", "min": 0.001, "max": 0.002}}])"));
  EXPECT_NE(msg.find("give radius or size"), std::string::npos) << msg;
  // the time-step check counts the smallest particle to come: 20 um spheres at dt 1e-6
  // (Rayleigh time 8.6e-7 s, limit 1.7e-7 s)
  msg = failure<coloc::ConfigError>(box(
      R"("inflow": [{"face": "xlo", "rate": 10, "size": {"type": "uniform", "min": 0.00002,
      "max": 0.002}}])"));
  EXPECT_NE(msg.find("particles.dt"), std::string::npos) << msg;
}

}  // namespace
