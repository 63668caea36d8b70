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

const PartitionStrategy& strategyOf(const Layouts& L) {
  return PartitionStrategy::named(L.strategy);
}

namespace {

void packBlocks(const Blocks& b, std::vector<int>& out) {
  out.insert(out.end(), b.dims.begin(), b.dims.end());
  for (int d = 0; d < 3; ++d) out.insert(out.end(), b.cuts[d].begin(), b.cuts[d].end());
}

Blocks unpackBlocks(const std::vector<int>& in, std::size_t& q) {
  Blocks b;
  for (int d = 0; d < 3; ++d) b.dims[d] = in.at(q++);
  for (int d = 0; d < 3; ++d) {
    const auto n = static_cast<std::size_t>(b.dims[d]) + 1;
    b.cuts[d].assign(in.begin() + static_cast<std::ptrdiff_t>(q),
                     in.begin() + static_cast<std::ptrdiff_t>(q + n));
    q += n;
  }
  return b;
}

}  // namespace

StrategyLayout layoutOnRoot(const Comm& comm, const GlobalGrid& grid,
                            const std::function<StrategyLayout()>& choose) {
  StrategyLayout l;
  std::string err;
  // [process grid?, own particle blocks?], then the blocks (dims, cuts) or 6 ints a box
  std::vector<int> packed;
  double num[4] = {1.0, 1.0, 0.0, 0.0};
  if (comm.isRoot()) {
    try {
      l = choose();
      packed = {l.isGrid() ? 1 : 0, l.particleBlocks ? 1 : 0};
      if (l.isGrid()) {
        packBlocks(*l.fluidBlocks, packed);
        if (l.particleBlocks) packBlocks(*l.particleBlocks, packed);
      } else {
        for (const IndexBox& b : l.fluid.box) {
          packed.insert(packed.end(), b.lo.begin(), b.lo.end());
          packed.insert(packed.end(), b.hi.begin(), b.hi.end());
        }
      }
      num[0] = l.modelledImbalance;
      num[1] = l.uniformImbalance;
      num[2] = l.maxCost;
      num[3] = l.meanCost;
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
  comm.broadcast(std::span<double>(num, 4));
  if (comm.isRoot()) return l;
  std::size_t q = 2;
  if (packed.at(0) == 1) {
    const Blocks fluid = unpackBlocks(packed, q);
    std::optional<Blocks> particles;
    if (packed.at(1) == 1) particles = unpackBlocks(packed, q);
    l = blocksLayout(grid, fluid, particles);
  } else {
    l.fluid.grid = grid;
    l.fluid.box.resize((packed.size() - 2) / 6);
    for (auto& b : l.fluid.box) {
      for (int d = 0; d < 3; ++d) b.lo[d] = packed[q++];
      for (int d = 0; d < 3; ++d) b.hi[d] = packed[q++];
    }
    l.particles = l.fluid;
  }
  l.modelledImbalance = num[0];
  l.uniformImbalance = num[1];
  l.maxCost = num[2];
  l.meanCost = num[3];
  return l;
}

Layouts runLayouts(const Comm& comm, const PartitionStrategy& strategy,
                   const StrategyLayout& layout, const CostModel& model) {
  const GlobalGrid& g = layout.fluid.grid;
  Layouts L{layout.isGrid() ? Decomposition::fromCuts(comm, g, layout.fluidBlocks->cuts)
                            : decompositionOf(comm, layout.fluid),
            std::nullopt,
            std::string(strategy.name()),
            model,
            layout.modelledImbalance,
            layout.uniformImbalance};
  if (layout.particleBlocks)
    L.particles = Decomposition::fromCuts(comm, g, layout.particleBlocks->cuts);
  return L;
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
