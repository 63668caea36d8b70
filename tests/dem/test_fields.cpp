// The particle field table (coloc/dem/fields.hpp): per-particle quantities added by one entry
// (ParticleStore::addField) travel with the built-in ones, at any rank count:
//  - ghost build: every ghost carries its owner's value (periodic images too); a field outside
//    the ghost operations is zero on ghosts;
//  - ghost update: a value the owners change between rebuilds reaches the ghosts in the next step;
//  - migration: after many steps (particles crossing ranks and periodic faces) every particle
//    still carries its own value;
//  - state: saveState carries the fields; a solver restored from it on another rank count (one
//    rank; and all rows given to rank 0) has every value, in owned rows and ghosts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dem_test_util.hpp"

namespace {

using coloc::dem::DemSolver;
using coloc::dem::DemState;
using coloc::dem::FieldInfo;
using coloc::dem::ParticleStore;
using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

// a dense frictional gas, periodic in x and y, walls in z: migration, periodic ghosts, rebuilds
const char* kBox = R"({
  "gravity": [0, 0, -9.81],
  "domain": {"length": [0.04, 0.04, 0.04], "cells": [8, 8, 8],
             "periodic": {"x": true, "y": true}},
  "particles": {
    "dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.7,
                   "friction": 0.5}],
    "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.04, 0.04, 0.04], "count": 2000,
                 "radius": 0.001, "gap": 0.02, "velocity": [1.0, -0.7, 0.0],
                 "velocity_spread": 0.4}]
  }
})";
constexpr long kN = 2000;

using coloc::dem::kOpGhostBuild;
using coloc::dem::kOpGhostUpdate;
using coloc::dem::kOpMigrate;
using coloc::dem::kOpState;

double tagOf(std::int64_t id) {
  return 0.5 + 3.0 * static_cast<double>(id);
}
double vecOf(std::int64_t id, int k) {
  return static_cast<double>(id) * (k + 1) - 7.0;
}

/// The test's fields: "tag" everywhere, "vec" (3 components) with the particle but never on
/// ghosts, "phase" refreshed on ghosts every step but not kept in the state.
void declare(ParticleStore& p) {
  p.addField("tag", 1, kOpGhostBuild | kOpMigrate | kOpState);
  p.addField("vec", 3, kOpMigrate | kOpState);
  p.addField("phase", 1, kOpGhostUpdate | kOpMigrate);
}

void setOwned(ParticleStore& p) {
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    p.field("tag")[i] = tagOf(p.id[i]);
    for (int k = 0; k < 3; ++k) p.field("vec", k)[i] = vecOf(p.id[i], k);
  }
}

/// Rows of particles whose tag (owned and ghosts) or vec (owned; zero on ghosts) is wrong.
long wrongRows(const ParticleStore& p) {
  long bad = 0;
  const auto& tag = p.field("tag");
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (tag[i] != tagOf(p.id[i])) ++bad;
    for (int k = 0; k < 3; ++k)
      if (p.field("vec", k)[i] != (i < p.nOwned ? vecOf(p.id[i], k) : 0.0)) ++bad;
  }
  return bad;
}

/// Every state field of every rank's owned rows, gathered on every rank, in table order.
std::vector<double> gatherRows(const coloc::Comm& comm, const ParticleStore& q, std::size_t& w) {
  std::vector<double> rows;
  w = 0;
  coloc::dem::forEachField(q, [&](const FieldInfo& fi, const auto*) {
    if (fi.ops & kOpState) w += static_cast<std::size_t>(fi.components);
  });
  for (std::size_t i = 0; i < q.nOwned; ++i)
    coloc::dem::forEachField(q, [&](const FieldInfo& fi, const auto* c) {
      if (fi.ops & kOpState)
        for (int k = 0; k < fi.components; ++k) rows.push_back(static_cast<double>(c[k][i]));
    });
  const auto counts = comm.allgather(static_cast<int>(rows.size()));
  std::vector<int> displ;
  std::vector<double> all(static_cast<std::size_t>(coloc::Comm::displacements(counts, displ)));
  MPI_Allgatherv(rows.data(), static_cast<int>(rows.size()), MPI_DOUBLE, all.data(), counts.data(),
                 displ.data(), MPI_DOUBLE, comm.raw());
  return all;
}

/// A state holding `rows` (as gatherRows packs them) with the extra fields of `like`.
DemState stateOf(const std::vector<double>& rows, std::size_t w, const DemState& like) {
  DemState s;
  s.time = like.time;
  s.steps = like.steps;
  s.rebuilds = like.rebuilds;
  s.flow = like.flow;
  auto& q = s.particles;
  for (const auto& e : like.particles.extra) q.addField(e.name, e.components, e.ops);
  const std::size_t n = rows.size() / w;
  coloc::dem::forEachField(q, [&](const FieldInfo& fi, auto* c) {
    for (int k = 0; k < fi.components; ++k) c[k].resize(n);
  });
  for (std::size_t i = 0; i < n; ++i) {
    const double* r = &rows[i * w];
    coloc::dem::forEachField(q, [&](const FieldInfo& fi, auto* c) {
      using T = typename std::remove_reference_t<decltype(c[0])>::value_type;
      if (fi.ops & kOpState)
        for (int k = 0; k < fi.components; ++k) c[k][i] = static_cast<T>(*r++);
    });
  }
  q.nOwned = n;
  return s;
}

TEST(ParticleFields, GhostsMigrationAndState) {
  Case a(kBox);
  const auto& comm = a.dec.comm();
  auto& p = a.p();
  declare(p);
  setOwned(p);
  EXPECT_THROW(p.addField("tag", 1, kOpState), coloc::Error);
  a.dem->rebuildNow();  // the ghosts made again, now with the fields
  const long ghosts = comm.sum(static_cast<long>(p.nGhost));
  EXPECT_GT(ghosts, 0);
  EXPECT_EQ(comm.sum(wrongRows(p)), 0) << "ghost build";

  // ghost update: the owners' phase, written before each step, is on the ghosts after it
  std::vector<std::int64_t> before(p.id.begin(), p.id.begin() + static_cast<long>(p.nOwned));
  std::sort(before.begin(), before.end());
  long stale = 0, updates = 0;
  const long long rebuilds0 = a.dem->rebuildCount();
  for (int s = 0; s < 400; ++s) {
    auto& ph = p.field("phase");
    for (std::size_t i = 0; i < p.nOwned; ++i) ph[i] = static_cast<double>(p.id[i] + 10 * s);
    const long long r0 = a.dem->rebuildCount();
    a.dem->substep();
    if (a.dem->rebuildCount() != r0) continue;  // a rebuild carries no phase to new ghosts
    ++updates;
    for (std::size_t i = p.nOwned; i < p.size(); ++i)
      if (p.field("phase")[i] != static_cast<double>(p.id[i] + 10 * s)) ++stale;
  }
  EXPECT_EQ(comm.sum(stale), 0) << "ghost update";
  EXPECT_GT(updates, 0);
  EXPECT_GT(a.dem->rebuildCount(), rebuilds0 + 3);
  // migration: particles that arrived from another rank keep their values
  long arrived = 0;
  for (std::size_t i = 0; i < p.nOwned; ++i)
    if (!std::binary_search(before.begin(), before.end(), p.id[i])) ++arrived;
  arrived = comm.sum(arrived);
  if (comm.size() > 1) {
    EXPECT_GT(arrived, 0);
  }
  EXPECT_EQ(comm.sum(wrongRows(p)), 0) << "migration";
  EXPECT_EQ(a.dem->globalCount(), kN);
  if (comm.isRoot())
    std::printf(
        "ranks %d: %ld ghosts at the start, %ld particles arrived from other ranks, %lld "
        "rebuilds, %ld steps without rebuild\n",
        comm.size(), ghosts, arrived, a.dem->rebuildCount() - rebuilds0, updates);

  // state: the fields in kOpState travel in DemState; restored on one rank, and all on rank 0
  const DemState st = a.dem->saveState();
  ASSERT_EQ(st.particles.extra.size(), 2u);  // tag and vec (phase is not in the state)
  EXPECT_EQ(st.particles.field("tag").size(), st.particles.nOwned);
  std::size_t w = 0;
  const std::vector<double> rows = gatherRows(comm, st.particles, w);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kN) * w);
  Case ser(kBox, kSelf, {1, 1, 1});
  DemSolver s(ser.dec, ser.cfg, ser.timers, stateOf(rows, w, st));
  EXPECT_EQ(s.particles().nOwned, static_cast<std::size_t>(kN));
  EXPECT_EQ(wrongRows(s.particles()), 0) << "restored on one rank";
  DemSolver z(a.dec, a.cfg, a.timers, stateOf(comm.isRoot() ? rows : std::vector<double>{}, w, st));
  EXPECT_EQ(comm.sum(wrongRows(z.particles())), 0) << "restored from rank 0";
  for (int k = 0; k < 50; ++k) {
    s.substep();
    z.substep();
  }
  EXPECT_EQ(wrongRows(s.particles()), 0);
  EXPECT_EQ(comm.sum(wrongRows(z.particles())), 0);
  EXPECT_EQ(z.globalCount(), kN);
}

}  // namespace
