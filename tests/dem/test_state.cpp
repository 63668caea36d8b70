// Checkpoint/restart state (DemState, saveState, the restoring constructor) and blow-up checks:
//  - same rank count, same decomposition: a run that saves its state at step 100 and goes on,
//    and a solver restored from that state, agree byte for byte after 100 more steps
//    (positions, velocities, angular velocities, forces, torques, contact histories);
//  - another rank count (the state gathered and restored on one rank, given to rank 0 only, or
//    split in arbitrary row blocks with the histories split apart from their holders): positions
//    and velocities within 1e-10 relative after 300 more steps;
//  - blow-up: a NaN velocity and a restored particle outside the box stop every rank with a
//    coloc::Error naming the particle, the rank and the step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include "dem_test_util.hpp"

namespace {

using coloc::dem::ContactHistory;
using coloc::dem::DemSolver;
using coloc::dem::DemState;
using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

// dense frictional gas between two walls (z) under gravity, periodic in x and y: many lasting
// contacts (histories), wall contacts, migration and rebuilds within 100 steps
const char* kBox = R"({
  "gravity": [0, 0, -9.81],
  "domain": {"length": [0.04, 0.04, 0.04], "cells": [8, 8, 8],
             "periodic": {"x": true, "y": true}},
  "particles": {
    "dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.7,
                   "friction": 0.5}],
    "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.04, 0.04, 0.04], "count": 5000,
                 "radius": 0.001, "gap": 0.02, "velocity": [0.3, -0.2, -0.5],
                 "velocity_spread": 0.6}]
  }
})";
constexpr long kN = 5000;

void setExternalForces(coloc::dem::ParticleStore& p) {
  for (std::size_t i = 0; i < p.nOwned; ++i) p.fExt[0][i] = 1e-5 * static_cast<double>(p.id[i] % 3);
}

constexpr int kRec = 25;
/// Flattens a state: 25 doubles per particle (id, material, radius, mass, x, v, omega, f, torque,
/// fExt, the position at the last rebuild) and 5 per history (holder, partner, shear).
void flatten(const DemState& s, std::vector<double>& parts, std::vector<double>& hist) {
  const auto& q = s.particles;
  for (std::size_t i = 0; i < q.nOwned; ++i) {
    parts.push_back(static_cast<double>(q.id[i]));
    parts.push_back(q.material[i]);
    parts.push_back(q.radius[i]);
    parts.push_back(q.mass[i]);
    for (const auto* a : {&q.x, &q.v, &q.omega, &q.f, &q.torque, &q.fExt})
      for (int k = 0; k < 3; ++k) parts.push_back((*a)[k][i]);
    for (int k = 0; k < 3; ++k) parts.push_back(s.xRebuild[static_cast<std::size_t>(k)][i]);
  }
  for (const auto& c : s.contacts) {
    hist.push_back(static_cast<double>(c.holder));
    hist.push_back(static_cast<double>(c.partner));
    hist.insert(hist.end(), c.shear.begin(), c.shear.end());
  }
}

/// A state from flat rows [a, b) of particles and [c, d) of histories.
DemState unflatten(const std::vector<double>& parts, std::size_t a, std::size_t b,
                   const std::vector<double>& hist, std::size_t c, std::size_t d,
                   const DemState& m) {
  DemState s;
  s.time = m.time;
  s.steps = m.steps;
  s.rebuilds = m.rebuilds;
  auto& q = s.particles;
  q.nOwned = b - a;
  for (std::size_t i = a; i < b; ++i) {
    const double* r = &parts[i * kRec];
    q.id.push_back(static_cast<std::int64_t>(r[0]));
    q.material.push_back(static_cast<int>(r[1]));
    q.radius.push_back(r[2]);
    q.mass.push_back(r[3]);
    int o = 4;
    for (auto* arr : {&q.x, &q.v, &q.omega, &q.f, &q.torque, &q.fExt})
      for (int k = 0; k < 3; ++k) (*arr)[k].push_back(r[o++]);
    for (int k = 0; k < 3; ++k) s.xRebuild[static_cast<std::size_t>(k)].push_back(r[o++]);
  }
  for (std::size_t h = c; h < d; ++h) {
    ContactHistory ch;
    ch.holder = static_cast<std::int64_t>(hist[5 * h]);
    ch.partner = static_cast<std::int64_t>(hist[5 * h + 1]);
    for (int k = 0; k < 3; ++k) ch.shear[static_cast<std::size_t>(k)] = hist[5 * h + 2 + k];
    s.contacts.push_back(ch);
  }
  return s;
}

std::vector<double> allgather(const coloc::Comm& comm, const std::vector<double>& v) {
  const auto counts = comm.allgather(static_cast<int>(v.size()));
  std::vector<int> displ;
  std::vector<double> out(static_cast<std::size_t>(coloc::Comm::displacements(counts, displ)));
  MPI_Allgatherv(v.data(), static_cast<int>(v.size()), MPI_DOUBLE, out.data(), counts.data(),
                 displ.data(), MPI_DOUBLE, comm.raw());
  return out;
}

/// Sorted rows of a flat table (rows of `w` doubles), by the first two entries.
std::vector<double> sortedRows(std::vector<double> v, int w) {
  const std::size_t n = v.size() / static_cast<std::size_t>(w);
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    const double* ra = &v[a * static_cast<std::size_t>(w)];
    const double* rb = &v[b * static_cast<std::size_t>(w)];
    return ra[0] != rb[0] ? ra[0] < rb[0] : ra[1] < rb[1];
  });
  std::vector<double> out;
  out.reserve(v.size());
  for (const auto i : idx)
    out.insert(out.end(), v.begin() + static_cast<std::ptrdiff_t>(i * static_cast<std::size_t>(w)),
               v.begin() + static_cast<std::ptrdiff_t>((i + 1) * static_cast<std::size_t>(w)));
  return out;
}

TEST(DemState, SameRanksBitwise) {
  Case a(kBox);
  setExternalForces(a.p());
  for (int s = 0; s < 100; ++s) a.dem->substep();
  DemState st = a.dem->saveState();
  EXPECT_EQ(st.steps, 100);
  EXPECT_EQ(st.particles.nGhost, 0u);
  const long long nc = a.dec.comm().sum(static_cast<long long>(st.contacts.size()));
  DemSolver b(a.dec, a.cfg, a.timers, std::move(st));
  EXPECT_EQ(b.time(), a.dem->time());
  EXPECT_EQ(b.rebuildCount(), a.dem->rebuildCount());
  for (int s = 0; s < 100; ++s) {
    a.dem->substep();
    b.substep();
  }
  EXPECT_EQ(b.time(), a.dem->time());
  EXPECT_EQ(b.rebuildCount(), a.dem->rebuildCount());
  // byte for byte on each rank: particles (with forces) and histories, sorted by id
  const DemState sa = a.dem->saveState(), sb = b.saveState();
  std::vector<double> pa, ha, pb, hb;
  flatten(sa, pa, ha);
  flatten(sb, pb, hb);
  pa = sortedRows(pa, kRec);
  pb = sortedRows(pb, kRec);
  ha = sortedRows(ha, 5);
  hb = sortedRows(hb, 5);
  long bad = 0;
  if (pa.size() != pb.size() || std::memcmp(pa.data(), pb.data(), pa.size() * 8) != 0) ++bad;
  if (ha.size() != hb.size() || std::memcmp(ha.data(), hb.data(), ha.size() * 8) != 0) ++bad;
  bad = a.dec.comm().sum(bad);
  const long long hist = a.dec.comm().sum(static_cast<long long>(sa.contacts.size()));
  const long long walls = a.dec.comm().sum(
      static_cast<long long>(std::count_if(sa.contacts.begin(), sa.contacts.end(),
                                           [](const ContactHistory& c) { return c.partner < 0; })));
  if (a.dec.comm().isRoot())
    std::printf(
        "ranks %d: %lld histories saved at step 100, %lld at step 200 (%lld with walls), "
        "%lld rebuilds; ranks differing: %ld\n",
        a.dec.size(), nc, hist, walls, a.dem->rebuildCount(), bad);
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(a.dem->globalCount(), kN);
  EXPECT_GT(nc, kN / 4);  // the case has lasting contacts
  EXPECT_GT(walls, 0);
  EXPECT_GT(a.dem->rebuildCount(), 4);
}

TEST(DemState, OtherRankCount) {
  Case a(kBox);
  setExternalForces(a.p());
  const auto& comm = a.dec.comm();
  for (int s = 0; s < 100; ++s) a.dem->substep();
  const DemState st = a.dem->saveState();
  std::vector<double> parts, hist;
  flatten(st, parts, hist);
  parts = allgather(comm, parts);
  hist = allgather(comm, hist);
  const std::size_t np = parts.size() / kRec, nh = hist.size() / 5;
  ASSERT_EQ(np, static_cast<std::size_t>(kN));
  const auto P = static_cast<std::size_t>(comm.size()), r = static_cast<std::size_t>(comm.rank());
  // serial, from the whole state
  Case ser(kBox, kSelf, {1, 1, 1});
  DemSolver s(ser.dec, ser.cfg, ser.timers, unflatten(parts, 0, np, hist, 0, nh, st));
  // all on rank 0
  DemSolver z(
      a.dec, a.cfg, a.timers,
      r == 0 ? unflatten(parts, 0, np, hist, 0, nh, st) : unflatten(parts, 0, 0, hist, 0, 0, st));
  // row blocks in reverse rank order, histories in blocks shifted by one rank (most histories
  // are not on their holder's rank)
  const std::size_t pr = P - 1 - r, hr = (r + 1) % P;
  DemSolver w(
      a.dec, a.cfg, a.timers,
      unflatten(parts, pr * np / P, (pr + 1) * np / P, hist, hr * nh / P, (hr + 1) * nh / P, st));
  for (int k = 0; k < 300; ++k) {
    a.dem->substep();
    s.substep();
    z.substep();
    w.substep();
  }
  const auto table = [&](DemSolver& d, const coloc::Comm& c) {
    std::vector<double> t(static_cast<std::size_t>(7 * kN), 0.0);
    const auto& p = d.particles();
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      const auto k = static_cast<std::size_t>(7 * p.id[i]);
      t[k] += 1;
      for (int e = 0; e < 3; ++e) {
        t[k + 1 + static_cast<std::size_t>(e)] = p.x[e][i];
        t[k + 4 + static_cast<std::size_t>(e)] = p.v[e][i];
      }
    }
    c.sumInPlace(std::span<double>(t));
    return t;
  };
  const auto ta = table(*a.dem, comm), ts = table(s, kSelf), tz = table(z, comm),
             tw = table(w, comm);
  double vscale = 0;
  for (long k = 0; k < kN; ++k)
    for (int e = 0; e < 3; ++e)
      vscale = std::max(vscale, std::fabs(ta[static_cast<std::size_t>(7 * k + 4 + e)]));
  double worst[3] = {0, 0, 0};
  long missing = 0;
  const std::vector<double>* others[3] = {&ts, &tz, &tw};
  for (int o = 0; o < 3; ++o)
    for (long k = 0; k < kN; ++k) {
      const auto b = static_cast<std::size_t>(7 * k);
      if ((*others[o])[b] != 1.0 || ta[b] != 1.0) ++missing;
      for (int e = 1; e < 7; ++e) {
        const double scale = e < 4 ? 0.04 : vscale;
        worst[o] = std::max(worst[o], std::fabs((*others[o])[b + static_cast<std::size_t>(e)] -
                                                ta[b + static_cast<std::size_t>(e)]) /
                                          scale);
      }
    }
  if (comm.isRoot())
    std::printf(
        "ranks %d -> 1 rank: %.3e, -> all on rank 0: %.3e, -> split rows: %.3e "
        "(relative to box / largest speed)\n",
        comm.size(), worst[0], worst[1], worst[2]);
  EXPECT_EQ(missing, 0);
  for (const double x : worst) EXPECT_LE(x, 1e-10);
}

/// Every rank runs `f`; returns this rank's coloc::Error message ("" if none).
template <class F>
std::string failure(F&& f) {
  try {
    f();
  } catch (const coloc::Error& e) {
    return e.what();
  }
  return "";
}

const char* kSmall = R"({
  "domain": {"length": [0.1, 0.1, 0.1], "cells": [10, 10, 10]},
  "particles": {"dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.9}],
    "sources": [{"type": "list", "radius": 0.002,
                 "positions": [0.02, 0.05, 0.05, 0.08, 0.05, 0.05, 0.05, 0.02, 0.08]}]}})";

TEST(DemState, NanVelocityStopsEveryRank) {
  Case c(kSmall);
  const auto msg = failure([&] {
    auto& p = c.p();
    for (std::size_t i = 0; i < p.nOwned; ++i)
      if (p.id[i] == 1) p.v[1][i] = std::nan("");
    for (int s = 0; s < 10; ++s) c.dem->substep();
  });
  EXPECT_NE(msg.find("particle 1 has a non-finite"), std::string::npos) << msg;
  EXPECT_NE(msg.find("on rank"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at step 0"), std::string::npos) << msg;
}

TEST(DemState, RestoredParticleOutsideTheBoxStopsEveryRank) {
  Case c(kSmall);
  DemState st = c.dem->saveState();
  for (std::size_t i = 0; i < st.particles.nOwned; ++i)
    if (st.particles.id[i] == 2) st.particles.x[2][i] = 0.13;
  const auto msg = failure([&] { DemSolver d(c.dec, c.cfg, c.timers, std::move(st)); });
  EXPECT_NE(msg.find("particle 2 left the box through the high z face"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at step 0"), std::string::npos) << msg;
}

TEST(DemState, OverlapMessageNamesStep) {
  Case c(kSmall);
  const auto msg = failure([&] {
    auto& p = c.p();
    for (std::size_t i = 0; i < p.nOwned; ++i)
      if (p.id[i] == 0) p.v[0][i] = -40.0;  // into the low x wall at 40 m/s
    for (int s = 0; s < 2000; ++s) c.dem->substep();
  });
  EXPECT_NE(msg.find("particle 0 overlaps a wall"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at step"), std::string::npos) << msg;
}

}  // namespace
