#include "coloc/coupling/layouts.hpp"

#include <algorithm>
#include <limits>
#include <span>

#include "coloc/core/error.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

StrategyInput strategyInput(const Config& cfg, int ranks) {
  StrategyInput in;
  in.grid = gridFromConfig(cfg);
  in.ranks = ranks;
  const auto dims = cfg.intVec3("partition.dims"), dem = cfg.intVec3("partition.dem_dims");
  for (int d = 0; d < 3; ++d) {
    in.dims[d] = static_cast<int>(dims[d]);
    in.demDims[d] = static_cast<int>(dem[d]);
  }
  in.minCells = minBlockCells(cfg);
  in.granularity = static_cast<int>(std::max<long long>(1, cfg.integer("particles.bin_cells")));
  return in;
}

StrategyBlocks chooseBlocksOnRoot(const Comm& comm, const std::string& strategy,
                                  const StrategyInput& in, const std::vector<double>& cost,
                                  bool costIsCount) {
  StrategyBlocks b;
  b.strategy = strategy;
  std::string err;
  std::vector<int> packed;
  double imb[2] = {1.0, 1.0};
  if (comm.isRoot()) {
    try {
      b = costIsCount ? chooseBlocks(strategy, in, {}, cost) : chooseBlocks(strategy, in, cost, {});
      for (const Blocks* blk : {&b.fluid, b.particles ? &*b.particles : nullptr}) {
        if (!blk) continue;
        for (int d = 0; d < 3; ++d) packed.push_back(blk->dims[d]);
        for (int d = 0; d < 3; ++d)
          packed.insert(packed.end(), blk->cuts[d].begin(), blk->cuts[d].end());
      }
      imb[0] = b.modelledImbalance;
      imb[1] = b.uniformImbalance;
    } catch (const Error& e) {
      err = e.what();
    }
  }
  err = comm.broadcast(err);
  if (!err.empty()) throw Error(err);
  int len = static_cast<int>(packed.size());
  comm.broadcast(std::span<int>(&len, 1));
  packed.resize(static_cast<std::size_t>(len));
  comm.broadcast(std::span<int>(packed));
  comm.broadcast(std::span<double>(imb, 2));
  if (comm.isRoot()) return b;
  std::size_t q = 0;
  const auto unpack = [&](Blocks& blk) {
    for (int d = 0; d < 3; ++d) blk.dims[d] = packed[q++];
    for (int d = 0; d < 3; ++d) {
      blk.cuts[d].assign(packed.begin() + static_cast<std::ptrdiff_t>(q),
                         packed.begin() + static_cast<std::ptrdiff_t>(q) + blk.dims[d] + 1);
      q += static_cast<std::size_t>(blk.dims[d]) + 1;
    }
  };
  unpack(b.fluid);
  if (q < packed.size()) {
    b.particles.emplace();
    unpack(*b.particles);
  }
  b.modelledImbalance = imb[0];
  b.uniformImbalance = imb[1];
  return b;
}

Layouts tiledLayoutsOnRoot(const Comm& comm, const Config& cfg, const std::vector<double>& cost,
                           const CostModel& model, const Decomposition* current,
                           std::array<double, 2>* verdict) {
  const StrategyInput in = strategyInput(cfg, comm.size());
  const int P = comm.size();
  std::vector<int> packed(static_cast<std::size_t>(6 * P));
  double imb[4] = {1.0, 1.0, 1.0, 1.0};  // new, uniform, current, gain
  std::string err;
  if (comm.isRoot()) {
    try {
      const double surface = cfg.number("partition.cost.halo_cell");
      const TiledLayout t = tiledStrategy(in, cost, surface);
      if (current) {
        TiledLayout now;
        now.layout = boxLayoutOf(*current);
        TiledOptions opt;
        opt.surfaceCost = surface;
        evaluateBoxes(cost, opt, now);
        imb[2] = now.imbalance();
        imb[3] = t.maxCost > 0 ? now.maxCost / t.maxCost : 1.0;
      }
      for (int r = 0; r < P; ++r)
        for (int d = 0; d < 3; ++d) {
          packed[static_cast<std::size_t>(6 * r + d)] =
              t.layout.box[static_cast<std::size_t>(r)].lo[d];
          packed[static_cast<std::size_t>(6 * r + 3 + d)] =
              t.layout.box[static_cast<std::size_t>(r)].hi[d];
        }
      imb[0] = t.imbalance();
      imb[1] = std::numeric_limits<double>::quiet_NaN();  // no process grid: null in reports
      try {
        BalancedLayout even;
        const Blocks u = uniformBlocks(in);
        even.dims = u.dims;
        even.cuts = u.cuts;
        evaluateLayout(in.grid, cost, even);
        imb[1] = even.imbalance();
      } catch (const ConfigError&) {
      }
    } catch (const Error& e) {
      err = e.what();
    }
  }
  err = comm.broadcast(err);
  if (!err.empty()) throw Error(err);
  comm.broadcast(std::span<int>(packed));
  comm.broadcast(std::span<double>(imb, 4));
  if (verdict) *verdict = {imb[2], imb[3]};
  std::vector<Int3> lo(static_cast<std::size_t>(P)), hi(lo.size());
  for (int r = 0; r < P; ++r)
    for (int d = 0; d < 3; ++d) {
      lo[static_cast<std::size_t>(r)][d] = packed[static_cast<std::size_t>(6 * r + d)];
      hi[static_cast<std::size_t>(r)][d] = packed[static_cast<std::size_t>(6 * r + 3 + d)];
    }
  return Layouts{Decomposition::fromBoxes(comm, in.grid, std::move(lo), std::move(hi)),
                 std::nullopt,
                 "tiled",
                 model,
                 imb[0],
                 imb[1]};
}

ParticleProbe probeParticles(const Config& cfg, const Decomposition& dec) {
  ParticleProbe out;
  if (cfg.at("particles.sources").empty()) return out;
  dem::CaseParticles all = dem::caseParticles(cfg, dec.grid());
  out.total = static_cast<long long>(all.x[0].size());
  out.rMin = all.rMin;
  out.rMax = all.rMax;
  const int me = dec.rank();
  if (dec.size() == 1) {
    out.x = std::move(all.x);
    return out;
  }
  for (std::size_t i = 0; i < all.x[0].size(); ++i)
    if (dec.ownerOfPoint({all.x[0][i], all.x[1][i], all.x[2][i]}) == me)
      for (int d = 0; d < 3; ++d) out.x[d].push_back(all.x[d][i]);
  return out;
}

std::vector<double> probeCellCostsOnRoot(const Config& cfg, const Decomposition& dec,
                                         const CostModel& model) {
  const ParticleProbe p = probeParticles(cfg, dec);
  return cellCostsOnRoot(dec, p.x[0], p.x[1], p.x[2], model);
}

}  // namespace coloc::coupling
