// The DEM on a tiled layout (issue 14): boxes from tiledBoxes on a clustered cost (not a process
// grid at 3, 5, 7 ranks), against a serial reference run on MPI_COMM_SELF in the same test.
//  - a bed settling under gravity between walls, periodic along x, with lasting contacts;
//  - a fully periodic gas drifting across the periodic faces and the box faces, edges, corners;
//  each after a few hundred steps: every particle exactly once, positions within 1e-10 of the
//  box edge, velocities and angular velocities within 1e-10 of their largest value, the same
//  contact histories (count per holder and partner equal, shear within 1e-10 of the largest).
//  - a process grid given as boxes: the same ghosts as the sweeps deliver, the same results;
//  - the serial run's state restored onto the boxes (all of it given to rank 0) continues as
//    the serial run does (1e-10);
//  - a particle moved across a box corner (into a box sharing no face with its own where the
//    layout has one) and one across the corner of a periodic box land on the owners of their
//    new (wrapped) positions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "coloc/partition/tiled.hpp"
#include "dem_test_util.hpp"
#include "tiled_layouts.hpp"

namespace {

using coloc::Decomposition;
using coloc::GlobalGrid;
using coloc::Int3;
using coloc::Real3;
using demtest::Case;
const coloc::Comm kSelf(MPI_COMM_SELF);

/// The case's grid split by tiledBoxes over this run's ranks, on a cost 20x heavier in the cells
/// with i < ni and k < nk (a cluster in a corner of the x-z plane); box bounds on multiples of
/// `granularity` cells (DEM bins of several cells).
Decomposition tiled(const std::string& text, int ni, int nk, int granularity = 1) {
  const GlobalGrid g = coloc::gridFromConfig(demtest::config(text));
  const coloc::Comm world = coloc::Comm::world();
  coloc::TiledOptions opt;
  opt.granularity = granularity;
  const auto cost = coloc::test::heapedCost(g, {ni, g.cells[1], nk}, 20.0);
  return coloc::decompositionOf(world, coloc::tiledBoxes(g, cost, world.size(), opt).layout);
}

/// Runs `steps` sub-steps of the case on the tiled layout and serially, and compares.
void matchSerial(const std::string& name, const std::string& text, long n, double length, int steps,
                 int ni, int nk, int granularity = 1) {
  Case par(text, tiled(text, ni, nk, granularity));
  Case ser(text, kSelf, {1, 1, 1});
  ASSERT_TRUE(par.dec.isTiled());
  // owner of every particle at the start, to count those that changed rank
  const auto owners = [&par, n] {
    std::vector<double> o(static_cast<std::size_t>(n), 0.0);
    for (std::size_t i = 0; i < par.p().nOwned; ++i)
      o[static_cast<std::size_t>(par.p().id[i])] = par.dec.rank();
    par.dec.comm().sumInPlace(std::span<double>(o));
    return o;
  };
  const auto own0 = owners();
  for (int s = 0; s < steps; ++s) {
    par.dem->substep();
    ser.dem->substep();
  }
  const auto own1 = owners();
  long moved = 0;
  for (long k = 0; k < n; ++k)
    moved += own0[static_cast<std::size_t>(k)] != own1[static_cast<std::size_t>(k)];
  const auto tp = demtest::table(par, n);
  const auto ts = demtest::table(ser, n);
  const demtest::TableDiff diff = demtest::compare(tp, ts, length);
  long missing = 0;
  for (long k = 0; k < n; ++k) missing += tp[static_cast<std::size_t>(10 * k)] != 1.0;
  const long long contacts = par.dec.comm().sum(par.dem->localContacts());
  const long long contactsSer = ser.dem->localContacts();
  // the contact histories (of the current lists: both runs rebuilt at the same steps)
  const auto hp = demtest::historyTable(par, n);
  const auto hs = demtest::historyTable(ser, n);
  double smax = 0, sdiff = 0;
  long histories = 0, histDiffer = 0;
  for (std::size_t k = 0; k < hs.size(); k += 4) {
    histories += static_cast<long>(hs[k]);
    if (hp[k] != hs[k]) ++histDiffer;
    for (std::size_t d = 1; d < 4; ++d) smax = std::max(smax, std::fabs(hs[k + d]));
  }
  for (std::size_t k = 0; k < hs.size(); k += 4)
    for (std::size_t d = 1; d < 4; ++d) sdiff = std::max(sdiff, std::fabs(hp[k + d] - hs[k + d]));
  if (par.dec.comm().isRoot()) {
    std::printf(
        "%s, %d ranks (tiled): max |dx|/L %.3e, |dv|/max|v| %.3e, |dw|/max|w| %.3e; particles "
        "that changed rank %ld, rebuilds %lld, contacts %lld (serial %lld), histories %ld, "
        "max |d shear|/max|shear| %.3e\n",
        name.c_str(), par.dec.size(), diff.x, diff.v, diff.omega, moved, par.dem->rebuildCount(),
        contacts, contactsSer, histories, smax > 0 ? sdiff / smax : 0.0);
    for (int r = 0; r < par.dec.size(); ++r) {
      const Int3 lo = par.dec.loOf(r), hi = par.dec.hiOf(r);
      std::printf("  box %d: [%d,%d) x [%d,%d) x [%d,%d)\n", r, lo[0], hi[0], lo[1], hi[1], lo[2],
                  hi[2]);
    }
  }
  EXPECT_EQ(par.dem->globalCount(), n);
  EXPECT_EQ(missing, 0);
  EXPECT_EQ(diff.countsDiffer, 0);
  EXPECT_LE(diff.x, 1e-10);  // reference: the serial run
  EXPECT_LE(diff.v, 1e-10);
  EXPECT_LE(diff.omega, 1e-10);
  EXPECT_EQ(contacts, contactsSer);
  EXPECT_EQ(histDiffer, 0);  // the same histories, each once per holder
  EXPECT_GT(histories, 20);  // the case has lasting contacts
  EXPECT_LE(sdiff, 1e-10 * smax);
  EXPECT_GT(par.dem->rebuildCount(), 0);
  if (par.dec.size() > 1) {
    EXPECT_GT(moved, 10);  // the case really migrates particles
  }
}

const char* kBed = R"({
  "gravity": [0, 0, -9.81],
  "domain": {"length": [0.04, 0.02, 0.03], "cells": [8, 4, 6], "periodic": {"x": true}},
  "particles": {
    "dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.5,
                   "friction": 0.5}],
    "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.02, 0.02, 0.012], "count": 300,
                 "radius": 0.0008, "radius_max": 0.001, "velocity": [0.8, 0.3, -0.6],
                 "velocity_spread": 0.8}]
  }
})";

TEST(DemTiled, SettlingBedMatchesSerial) {
  matchSerial("bed", kBed, 300, 0.04, 400, 4, 3);
}

const char* kGas = R"({
  "domain": {"length": [0.03, 0.02, 0.03], "cells": [6, 4, 6],
             "periodic": {"x": true, "y": true, "z": true}},
  "particles": {
    "dt": 1e-5,
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.9,
                   "friction": 0.5, "rolling_friction": 0.1}],
    "sources": [{"type": "random", "lo": [0, 0, 0], "hi": [0.03, 0.02, 0.03], "count": 400,
                 "radius": 0.001, "velocity": [1.5, -1.0, 1.2], "velocity_spread": 1.0}]
  }
})";

TEST(DemTiled, PeriodicGasMatchesSerial) {
  matchSerial("gas", kGas, 400, 0.03, 400, 3, 3);
}

TEST(DemTiled, ThinBoxesOfTwoCellBinsMatchSerial) {
  // cells smaller than the range along x and z: bins of 2 cells, boxes on even cells, one bin
  // thick at the most ranks (a particle can be a ghost on both sides of its box)
  std::string text = kGas;
  const std::string key = R"("cells": [6, 4, 6])";
  text.replace(text.find(key), key.size(), R"("cells": [16, 8, 16])");
  matchSerial("gas, bins of 2 cells", text, 400, 0.03, 300, 6, 6, 2);
}

TEST(DemTiled, ProcessGridAsBoxesHasTheSweepsGhosts) {
  // the uniform process grid and the same blocks as a tiled layout: the sweeps and the targets
  // deliver the same ghosts to every rank, and the runs agree bit for bit
  // (a box long enough along x for a process grid of up to 7 ranks)
  const long n = 400;
  std::string text = kGas;
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{R"("length": [0.03, 0.02, 0.03], "cells": [6, 4, 6])",
                                            R"("length": [0.07, 0.02, 0.03], "cells": [14, 4, 6])"},
        {R"("hi": [0.03, 0.02, 0.03])", R"("hi": [0.07, 0.02, 0.03])"}})
    text.replace(text.find(from), from.size(), to);
  Case cart(text);
  Case boxes(text, coloc::decompositionOf(coloc::Comm::world(), coloc::boxLayoutOf(cart.dec)));
  ASSERT_FALSE(cart.dec.isTiled());
  ASSERT_TRUE(boxes.dec.isTiled());
  long long ghostsDiffer = 0;
  for (int s = 0; s < 300; ++s) {
    cart.dem->substep();
    boxes.dem->substep();
    ghostsDiffer += cart.p().nGhost != boxes.p().nGhost;
  }
  const auto tc = demtest::table(cart, n);
  const auto tb = demtest::table(boxes, n);
  long differ = 0;
  for (std::size_t k = 0; k < tc.size(); ++k) differ += tc[k] != tb[k];
  const long long ghosts = cart.dec.comm().sum(static_cast<long long>(cart.p().nGhost));
  if (cart.dec.comm().isRoot())
    std::printf("process grid %d x %d x %d as boxes: %lld ghosts, %ld values differ\n",
                cart.dec.dims()[0], cart.dec.dims()[1], cart.dec.dims()[2], ghosts, differ);
  EXPECT_EQ(cart.dec.comm().sum(ghostsDiffer), 0);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(ghosts, 0);
}

TEST(DemTiled, RestoredOntoBoxesMatchesSerial) {
  // the serial run's state at step 150 (with its histories and rebuild positions) given to rank 0
  // of the tiled layout only: the restore sends each particle and history to the owner of its box
  const long n = 300;
  Case ser(kBed, kSelf, {1, 1, 1});
  for (int s = 0; s < 150; ++s) ser.dem->substep();
  coloc::dem::DemState st = ser.dem->saveState();
  Case par(kBed, tiled(kBed, 4, 3));
  if (!par.dec.comm().isRoot()) {
    st.particles = coloc::dem::ParticleStore{};
    st.contacts.clear();
    st.contactRow.clear();
    st.xRebuild = {};
  }
  par.dem = std::make_unique<coloc::dem::DemSolver>(par.dec, par.cfg, par.timers, std::move(st));
  for (int s = 0; s < 150; ++s) {
    par.dem->substep();
    ser.dem->substep();
  }
  const demtest::TableDiff diff =
      demtest::compare(demtest::table(par, n), demtest::table(ser, n), 0.04);
  if (par.dec.comm().isRoot())
    std::printf("restored onto %d boxes: max |dx|/L %.3e, |dv|/max|v| %.3e, |dw|/max|w| %.3e\n",
                par.dec.size(), diff.x, diff.v, diff.omega);
  EXPECT_EQ(par.dem->globalCount(), n);
  EXPECT_EQ(diff.countsDiffer, 0);
  EXPECT_LE(diff.x, 1e-10);
  EXPECT_LE(diff.v, 1e-10);
  EXPECT_LE(diff.omega, 1e-10);
}

// ---------------------------------------------------------------------------------------------
// a move across a box corner

const char* kCorner = R"({
  "domain": {"length": [0.04, 0.02, 0.03], "cells": [8, 4, 6],
             "periodic": {"x": true, "y": true, "z": true}},
  "particles": {
    "dt": 1e-5, "materials": [{"density": 2500, "young": 1e7}],
    "sources": [{"type": "list", "radius": 0.001, "positions": [POS]}]}})";

/// True when boxes a and b touch along at least two axes (they share an edge or a corner, no
/// face) or not at all.
bool noCommonFace(const Decomposition& dec, int a, int b) {
  int touch = 0;
  for (int d = 0; d < 3; ++d)
    touch += dec.hiOf(a)[d] == dec.loOf(b)[d] || dec.hiOf(b)[d] == dec.loOf(a)[d];
  return touch != 1;
}

TEST(DemTiled, MigrationAcrossABoxCorner) {
  const std::string text0 = kCorner;
  const Decomposition probe =
      tiled(std::string(text0).replace(text0.find("POS"), 3, "0.01, 0.01, 0.01"), 4, 3);
  const GlobalGrid& g = probe.grid();
  // a cell corner with the cells on either side of it along a diagonal owned by two boxes
  // sharing no face (where the layout has one), else by two different boxes (else: none, one
  // rank: the periodic move below is the test)
  Int3 node{-1, -1, -1}, dir{1, 1, 1};
  bool edgeOnly = false;
  for (int k = 1; k < g.cells[2] && !edgeOnly; ++k)
    for (int j = 1; j < g.cells[1] && !edgeOnly; ++j)
      for (int i = 1; i < g.cells[0] && !edgeOnly; ++i)
        for (int s = 0; s < 4 && !edgeOnly; ++s) {
          const Int3 dv{1, s & 1 ? -1 : 1, s & 2 ? -1 : 1};
          const Int3 c0{dv[0] > 0 ? i - 1 : i, dv[1] > 0 ? j - 1 : j, dv[2] > 0 ? k - 1 : k};
          const Int3 c1{dv[0] > 0 ? i : i - 1, dv[1] > 0 ? j : j - 1, dv[2] > 0 ? k : k - 1};
          const int a = probe.ownerOfCell(c0), b = probe.ownerOfCell(c1);
          if (a == b) continue;
          if (node[0] < 0 || noCommonFace(probe, a, b)) {
            node = {i, j, k};
            dir = dv;
            edgeOnly = noCommonFace(probe, a, b);
          }
        }
  const double delta = 0.1 * g.spacing(0);
  Real3 p0{}, p1{}, q0{}, q1{};
  for (int d = 0; d < 3; ++d) {
    const double c =
        node[0] < 0 ? g.origin[d] + 0.5 * g.length[d] : g.origin[d] + node[d] * g.spacing(d);
    p0[d] = c - dir[d] * delta;
    p1[d] = c + dir[d] * delta;
    // the second particle leaves the box through the corner at the origin
    q0[d] = g.origin[d] + delta;
    q1[d] = g.origin[d] - delta;
  }
  std::ostringstream pos;
  pos.precision(17);
  pos << p0[0] << ", " << p0[1] << ", " << p0[2] << ", " << q0[0] << ", " << q0[1] << ", " << q0[2];
  std::string text = text0;
  text.replace(text.find("POS"), 3, pos.str());
  Case run(text, tiled(text, 4, 3));
  ASSERT_EQ(run.dem->globalCount(), 2);
  // the moves: particle 0 across the cell corner, particle 1 out through the box's corner
  auto& p = run.p();
  for (std::size_t i = 0; i < p.nOwned; ++i)
    for (int d = 0; d < 3; ++d) p.x[d][i] = p.id[i] == 0 ? p1[d] : q1[d];
  const int from0 = run.dec.ownerOfPoint(p0), from1 = run.dec.ownerOfPoint(q0);
  run.dem->rebuildNow();
  Real3 wrapped{};
  for (int d = 0; d < 3; ++d) wrapped[d] = q1[d] + g.length[d];
  const int to[2] = {run.dec.ownerOfPoint(p1), run.dec.ownerOfPoint(wrapped)};
  if (run.dec.comm().isRoot())
    std::printf(
        "%d ranks: particle 0 from rank %d to %d across cell corner (%d, %d, %d), boxes sharing "
        "%s; particle 1 from rank %d to %d through the periodic corner\n",
        run.dec.size(), from0, to[0], node[0], node[1], node[2],
        edgeOnly ? "no face" : "a face (no edge-only pair in this layout)", from1, to[1]);
  if (run.dec.size() >= 4) {
    EXPECT_TRUE(edgeOnly) << "expected an edge or corner neighbour";
  }
  long long held[2] = {0, 0};
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    const auto id = static_cast<std::size_t>(p.id[i]);
    ASSERT_LT(id, 2U);
    ++held[id];
    EXPECT_EQ(run.dec.rank(), to[id]) << "particle " << id;
    for (int d = 0; d < 3; ++d)
      EXPECT_DOUBLE_EQ(p.x[d][i], id == 0 ? p1[d] : wrapped[d]) << "particle " << id;
  }
  EXPECT_EQ(run.dec.comm().sum(held[0]), 1);
  EXPECT_EQ(run.dec.comm().sum(held[1]), 1);
}

}  // namespace
