// The DEM's particle exchange alone (dem/src/exchange.hpp, issue 28): no solver, no contact model.
// A box of 9 x 7 x 5 cells (no rank count divides it), periodic along x and z, walls along y,
// cut as a process grid (the uniform blocks, and slabs along x whose y and z are periodic over
// one block along z) and as tiled boxes (tiledBoxes on a cost heaped in a corner). Particles are
// moved by up to 0.9 bins (across block faces, edges, corners and the periodic faces) for a few
// rounds of migrate + buildGhosts + updateGhosts, and every round checks against a global list
// every rank holds:
//  - every particle owned by exactly one rank (ids, so the global count too), at its wrapped
//    position, on the rank whose block holds it (the owner rule written out here, not Bins');
//  - its fields and its contact-history rows arrived as sent (migrant rows);
//  - every particle whose position (or periodic image) lies within the interaction range of a
//    block other than its own (or as an image of its own) is a ghost there, once, at that image;
//    every ghost is such an image of its owner, within the range of the block;
//  - after the owned particles move and updateGhosts, every ghost is at its owner's new position
//    plus the same periodic shift, with its new velocity.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "coloc/core/timers.hpp"
#include "coloc/partition/tiled.hpp"
#include "exchange.hpp"
#include "rows.hpp"
#include "tiled_layouts.hpp"

namespace {

using coloc::Comm;
using coloc::Decomposition;
using coloc::GlobalGrid;
using coloc::Int3;
namespace detail = coloc::dem::detail;

constexpr int kN = 700;      // particles
constexpr double kRc = 0.7;  // interaction range (bins of one cell, edge 1)
constexpr int kRounds = 3;

GlobalGrid grid() {
  GlobalGrid g;
  g.cells = {9, 7, 5};
  g.length = {9.0, 7.0, 5.0};
  g.origin = {-1.0, 0.5, 2.0};
  g.periodic = {true, false, true};
  return g;
}

/// Uniform in [0, 1), the same on every rank.
double uniform(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

struct Expected {
  std::vector<std::array<double, 3>> x;  // every particle's position as its owner holds it
  std::vector<std::array<double, 3>> v;
};

/// The rank whose box holds x (clamped into the box), from the decomposition's boxes.
int ownerOf(const Decomposition& dec, const GlobalGrid& g, const std::array<double, 3>& x) {
  Int3 c{};
  for (int d = 0; d < 3; ++d)
    c[d] = std::clamp(static_cast<int>(std::floor((x[d] - g.origin[d]) / g.spacing(d))), 0,
                      g.cells[d] - 1);
  for (int r = 0; r < dec.size(); ++r) {
    const Int3 lo = dec.loOf(r), hi = dec.hiOf(r);
    bool in = true;
    for (int d = 0; d < 3; ++d) in = in && lo[d] <= c[d] && c[d] < hi[d];
    if (in) return r;
  }
  return -1;
}

/// x wrapped into the box on the periodic axes (as migration wraps it).
std::array<double, 3> wrapped(const GlobalGrid& g, std::array<double, 3> x) {
  for (int d = 0; d < 3; ++d) {
    if (!g.periodic[d]) continue;
    if (x[d] < g.origin[d]) x[d] += g.length[d];
    if (x[d] >= g.origin[d] + g.length[d]) x[d] -= g.length[d];
  }
  return x;
}

int histories(std::int64_t id) {
  return static_cast<int>(id % 4);
}
double historyKey(std::int64_t id, int e) {
  return static_cast<double>(1000 * id + e);
}
std::array<double, 3> historyShear(std::int64_t id, int e) {
  return {static_cast<double>(id), 0.25 * e, -0.5 * static_cast<double>(id)};
}

void addOwned(coloc::dem::ParticleStore& p, detail::HistoryPool& h, std::int64_t id,
              const std::array<double, 3>& x, const std::array<double, 3>& v) {
  const std::size_t i = p.nOwned;
  detail::resizeAll(p, i + 1);
  p.nOwned = i + 1;
  p.id[i] = id;
  p.material[i] = static_cast<int>(id % 3);
  p.radius[i] = 0.1 + 0.001 * static_cast<double>(id % 7);
  p.mass[i] = 2.0 + static_cast<double>(id);
  for (std::size_t d = 0; d < 3; ++d) {
    p.x[d][i] = x[d];
    p.v[d][i] = v[d];
    p.omega[d][i] = -v[d];
    p.fExt[d][i] = 0.5 * static_cast<double>(id) + static_cast<double>(d);
  }
  for (int e = 0; e < histories(id); ++e) {
    h.hKey.push_back(historyKey(id, e));
    for (const double s : historyShear(id, e)) h.hS.push_back(s);
  }
  h.hStart.push_back(static_cast<int>(h.hKey.size()));
}

/// Runs the rounds on `dec`.
void exercise(const Decomposition& dec) {
  const GlobalGrid g = dec.grid();
  const Comm& comm = dec.comm();
  const int me = comm.rank();
  coloc::dem::BinLayout layout;
  for (int d = 0; d < 3; ++d) {
    layout.size[static_cast<std::size_t>(d)] = g.spacing(d);
    layout.globalBins[static_cast<std::size_t>(d)] = g.cells[d];
  }
  detail::Bins bins;
  bins.setup(g, layout, dec.lo(), dec.hi());
  coloc::dem::ParticleStore p;
  detail::HistoryPool hist;
  hist.hStart.assign(1, 0);
  coloc::Timers timers;
  const auto ex = detail::makeExchange({.dec = dec,
                                        .comm = comm,
                                        .timers = timers,
                                        .p = p,
                                        .hist = hist,
                                        .bins = bins,
                                        .rc = kRc,
                                        .where = [] { return std::string(" (test)"); }},
                                       layout);

  // the particles: random, plus some on block and box faces (a bin edge exactly, and just off it)
  std::mt19937_64 rng(20261205);
  Expected e;
  e.x.resize(kN);
  e.v.resize(kN);
  for (int k = 0; k < kN; ++k) {
    auto& x = e.x[static_cast<std::size_t>(k)];
    for (int d = 0; d < 3; ++d) {
      const double L = g.length[d];
      x[d] = g.origin[d] + uniform(rng) * L;
      if (k % 5 == 0) {  // on a cell edge, or 1e-12 off it
        const double edge = g.origin[d] + std::floor(uniform(rng) * g.cells[d]) * g.spacing(d);
        x[d] = edge + (k % 3 - 1) * 1e-12;
        if (x[d] < g.origin[d]) x[d] = g.origin[d];
      }
    }
    e.v[static_cast<std::size_t>(k)] = {1e-3 * k, -2e-3 * k, 0.5};
  }
  for (int k = 0; k < kN; ++k)
    if (ownerOf(dec, g, e.x[static_cast<std::size_t>(k)]) == me)
      addOwned(p, hist, k, e.x[static_cast<std::size_t>(k)], e.v[static_cast<std::size_t>(k)]);

  for (int round = 0; round < kRounds; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    // every particle moves by up to 0.9 bins along each axis (the walls stop it along y); some
    // particles near a periodic face are pushed across it
    for (int k = 0; k < kN; ++k) {
      auto& x = e.x[static_cast<std::size_t>(k)];
      for (int d = 0; d < 3; ++d) {
        double dx = (2 * uniform(rng) - 1) * 0.9 * g.spacing(d);
        if (g.periodic[d] && k % 11 == round) {
          const double lo = x[d] - g.origin[d], hi = g.origin[d] + g.length[d] - x[d];
          if (lo < 0.5) dx = -0.6;
          if (hi < 0.5) dx = 0.6;
        }
        x[d] += dx;
        if (!g.periodic[d]) x[d] = std::clamp(x[d], g.origin[d], g.origin[d] + g.length[d]);
      }
      e.v[static_cast<std::size_t>(k)][0] += 1.0;
    }
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      const auto k = static_cast<std::size_t>(p.id[i]);
      for (std::size_t d = 0; d < 3; ++d) {
        p.x[d][i] = e.x[k][d];
        p.v[d][i] = e.v[k][d];
        p.omega[d][i] = -e.v[k][d];
      }
    }
    for (auto& x : e.x) x = wrapped(g, x);
    long long moved = 0;  // particles that change rank (the rounds must move some)
    for (std::size_t i = 0; i < p.nOwned; ++i)
      moved += ownerOf(dec, g, e.x[static_cast<std::size_t>(p.id[i])]) != me ? 1 : 0;
    if (comm.size() > 1) {
      EXPECT_GT(comm.sum(moved), 0);
    }

    // --- migration
    ex->migrate();
    ASSERT_EQ(p.nGhost, 0u);
    ASSERT_EQ(hist.hStart.size(), p.nOwned + 1);
    ASSERT_EQ(hist.hKey.size(), static_cast<std::size_t>(hist.hStart.back()));
    ASSERT_EQ(hist.hS.size(), 3 * hist.hKey.size());
    std::vector<double> owners(kN, 0.0);
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      const std::int64_t id = p.id[i];
      ASSERT_TRUE(id >= 0 && id < kN);
      const auto k = static_cast<std::size_t>(id);
      owners[k] += 1;
      const std::array<double, 3> x = {p.x[0][i], p.x[1][i], p.x[2][i]};
      EXPECT_EQ(x, e.x[k]) << "particle " << id;
      EXPECT_EQ(ownerOf(dec, g, x), me) << "particle " << id << " owned outside its block";
      EXPECT_EQ(p.material[i], id % 3);
      EXPECT_EQ(p.mass[i], 2.0 + static_cast<double>(id));
      for (std::size_t d = 0; d < 3; ++d) {
        EXPECT_EQ(p.v[d][i], e.v[k][d]);
        EXPECT_EQ(p.omega[d][i], -e.v[k][d]);
        EXPECT_EQ(p.fExt[d][i], 0.5 * static_cast<double>(id) + static_cast<double>(d));
      }
      const auto h0 = static_cast<std::size_t>(hist.hStart[i]);
      ASSERT_EQ(hist.hStart[i + 1] - hist.hStart[i], histories(id)) << "particle " << id;
      for (int h = 0; h < histories(id); ++h) {
        const std::size_t at = h0 + static_cast<std::size_t>(h);
        EXPECT_EQ(hist.hKey[at], historyKey(id, h));
        const auto s = historyShear(id, h);
        for (std::size_t c = 0; c < 3; ++c) EXPECT_EQ(hist.hS[3 * at + c], s[c]);
      }
    }
    comm.sumInPlace(std::span<double>(owners));
    for (int k = 0; k < kN; ++k)
      ASSERT_EQ(owners[static_cast<std::size_t>(k)], 1.0)
          << "particle " << k << " owned by " << owners[static_cast<std::size_t>(k)] << " ranks";

    // --- ghosts: exactly the images within the range of this block
    ex->buildGhosts();
    ASSERT_EQ(p.size(), p.nOwned + p.nGhost);
    const Int3 blo = dec.lo(), bhi = dec.hi();
    const auto inRange = [&](const std::array<double, 3>& y, double margin) {
      for (int d = 0; d < 3; ++d) {
        const double lo = g.origin[d] + blo[d] * g.spacing(d) - kRc,
                     hi = g.origin[d] + bhi[d] * g.spacing(d) + kRc;
        if (!(y[d] >= lo + margin && y[d] < hi - margin)) return false;
      }
      return true;
    };
    using Image = std::tuple<std::int64_t, int, int, int>;  // id, periods along x, y, z
    std::map<Image, std::size_t> ghostAt;
    for (std::size_t i = p.nOwned; i < p.size(); ++i) {
      const std::int64_t id = p.id[i];
      ASSERT_TRUE(id >= 0 && id < kN);
      const auto k = static_cast<std::size_t>(id);
      const std::array<double, 3> y = {p.x[0][i], p.x[1][i], p.x[2][i]};
      std::array<int, 3> n{};
      for (std::size_t d = 0; d < 3; ++d) {
        n[d] = static_cast<int>(std::lround((y[d] - e.x[k][d]) / g.length[d]));
        EXPECT_TRUE(n[d] == 0 || g.periodic[d]) << "ghost " << id << " shifted along a wall axis";
        EXPECT_EQ(y[d], e.x[k][d] + n[d] * g.length[d]) << "ghost " << id << " axis " << d;
      }
      EXPECT_TRUE(inRange(y, -1e-9)) << "ghost " << id << " beyond the range of the block";
      EXPECT_FALSE((n == std::array<int, 3>{}) && ownerOf(dec, g, e.x[k]) == me)
          << "ghost " << id << " of an owned particle, unshifted";
      EXPECT_EQ(p.radius[i], 0.1 + 0.001 * static_cast<double>(id % 7));
      EXPECT_EQ(p.material[i], id % 3);
      EXPECT_EQ(p.v[0][i], e.v[k][0]);
      const bool fresh = ghostAt.emplace(Image{id, n[0], n[1], n[2]}, i).second;
      EXPECT_TRUE(fresh) << "ghost " << id << " twice at one image";
    }
    long long missing = 0;
    for (int k = 0; k < kN; ++k) {
      const auto& x = e.x[static_cast<std::size_t>(k)];
      const bool mine = ownerOf(dec, g, x) == me;
      for (int nz = -1; nz <= 1; ++nz)
        for (int ny = -1; ny <= 1; ++ny)
          for (int nx = -1; nx <= 1; ++nx) {
            const std::array<int, 3> n = {nx, ny, nz};
            bool legal = !(mine && nx == 0 && ny == 0 && nz == 0);
            std::array<double, 3> y{};
            for (std::size_t d = 0; d < 3; ++d) {
              legal = legal && (n[d] == 0 || g.periodic[d]);
              y[d] = x[d] + n[d] * g.length[d];
            }
            if (!legal || !inRange(y, 1e-6)) continue;
            if (ghostAt.count(Image{k, nx, ny, nz}) == 0) {
              ++missing;
              ADD_FAILURE() << "rank " << me << ": particle " << k << " (image " << nx << ny << nz
                            << ") within range of the block is no ghost here";
            }
          }
    }
    EXPECT_EQ(missing, 0);
    EXPECT_GT(comm.sum(static_cast<long long>(p.nGhost)), 0);  // images at least
    if (comm.size() > 1) {
      EXPECT_GT(ex->bytes(), 0u);
    }

    // --- ghost update: the owned particles move (less than the skin), the ghosts follow
    for (int k = 0; k < kN; ++k) {
      auto& x = e.x[static_cast<std::size_t>(k)];
      for (int d = 0; d < 3; ++d) {
        x[d] += 0.01 * std::sin(k + 3.0 * d + round);
        if (!g.periodic[d]) x[d] = std::clamp(x[d], g.origin[d], g.origin[d] + g.length[d]);
      }
      e.v[static_cast<std::size_t>(k)][1] -= 2.0;
    }
    for (std::size_t i = 0; i < p.nOwned; ++i)
      for (std::size_t d = 0; d < 3; ++d) {
        p.x[d][i] = e.x[static_cast<std::size_t>(p.id[i])][d];
        p.v[d][i] = e.v[static_cast<std::size_t>(p.id[i])][d];
      }
    ex->updateGhosts();
    for (const auto& [image, i] : ghostAt) {
      const auto k = static_cast<std::size_t>(std::get<0>(image));
      const int n[3] = {std::get<1>(image), std::get<2>(image), std::get<3>(image)};
      for (std::size_t d = 0; d < 3; ++d) {
        EXPECT_EQ(p.x[d][i], e.x[k][d] + n[d] * g.length[d]) << "ghost " << k << " axis " << d;
        EXPECT_EQ(p.v[d][i], e.v[k][d]) << "ghost " << k;
      }
    }
  }
}

TEST(DemExchange, ProcessGrid) {
  const Decomposition dec = Decomposition::uniform(Comm::world(), grid());
  exercise(dec);
}

TEST(DemExchange, ProcessGridSlabs) {
  // slabs along x: y and z whole (z periodic over one block: images of the block's own particles)
  const Decomposition dec =
      Decomposition::uniform(Comm::world(), grid(), {Comm::world().size(), 1, 1});
  exercise(dec);
}

TEST(DemExchange, TiledBoxes) {
  const GlobalGrid g = grid();
  const Comm world = Comm::world();
  const auto cost = coloc::test::heapedCost(g, {3, 7, 2}, 20.0);
  const Decomposition dec =
      coloc::decompositionOf(world, coloc::tiledBoxes(g, cost, world.size()).layout);
  if (world.size() > 2) {
    EXPECT_TRUE(dec.isTiled());
  }
  exercise(dec);
}

}  // namespace
