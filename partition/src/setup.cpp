#include "coloc/partition/setup.hpp"

#include "coloc/core/run_config.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc {

void declareDomainConfig(Schema& s) {
  s.vec3("domain.origin", Real3{0, 0, 0}, "lower corner of the box (m)");
  s.vec3("domain.length", std::nullopt, "size of the box along x, y, z (m)", Range::positive());
  s.intVec3("domain.cells", std::nullopt, "number of cells along x, y, z", Range::atLeast(1));
  s.boolean("domain.periodic.x", false, "periodic along x");
  s.boolean("domain.periodic.y", false, "periodic along y");
  s.boolean("domain.periodic.z", false, "periodic along z");
  s.string(
      "partition.strategy", "uniform",
      "uniform: even Cartesian blocks shared by fluid and particles; balanced: one Cartesian "
      "grid for both, cuts placed by the cost model partition.cost.*; independent: the "
      "baseline, the DEM on its own blocks and every fluid-particle transfer by MPI; tiled: one "
      "box per rank by recursive bisection of the cost model (no process grid, any rank "
      "count)",
      PartitionStrategy::names());
  s.number("partition.cost.cell", 1.0, "balanced, tiled: modelled cost of a cell per step",
           Range::nonNegative());
  s.number("partition.cost.particle", 2.0, "balanced, tiled: modelled cost of a particle per step",
           Range::nonNegative());
  s.number("partition.cost.halo_cell", 0.0,
           "tiled: modelled cost of a halo cell of a box per step (ghost and halo "
           "work; the surface term of the bisection)",
           Range::nonNegative());
  s.integer("partition.calibrate_steps", 0,
            "balanced, tiled: measure the two costs over this many steps on uniform blocks first "
            "(0: use partition.cost.*)",
            Range::nonNegative());
  s.integer(
      "partition.rebalance_interval", 0,
      "balanced, tiled: every this many steps, place the cuts anew for the particles as they are "
      "(weights from the run's own phase timers) and move cells and particles together "
      "when it pays (0: never)",
      Range::nonNegative());
  s.number(
      "partition.rebalance_threshold", 1.05,
      "balanced, tiled: re-balance only when the modelled largest block cost drops by this factor",
      Range::atLeast(1.0));
  s.string("partition.rebalance_weights", "measured",
           "the weights a re-balance places the cuts with: measured (seconds per cell and per "
           "particle from the run's own phase timers) or case (partition.cost.cell and "
           "partition.cost.particle: the same cuts on every run, for reproducible runs)",
           {"measured", "case"});
  s.string("partition.rebalance_move", "memory",
           "how a re-balance moves the run: memory (fields remapped and particles sent to their "
           "new owners) or file (the former path through a scratch restart checkpoint "
           "rebalance.tmp.h5 in the output folder; kept to time the two side by side)",
           {"memory", "file"});
  s.intVec3("partition.dem_dims", std::array<long long, 3>{0, 0, 0},
            "independent: the DEM's process grid (0: balanced by particle count on a grid other "
            "than the fluid's)",
            Range::nonNegative());
  s.intVec3("partition.dims", std::array<long long, 3>{0, 0, 0},
            "process grid; 0 along an axis lets MPI_Dims_create choose", Range::nonNegative());
}

GlobalGrid gridFromConfig(const Config& cfg) {
  GlobalGrid g;
  g.origin = cfg.vec3("domain.origin");
  g.length = cfg.vec3("domain.length");
  const auto c = cfg.intVec3("domain.cells");
  for (int d = 0; d < 3; ++d) {
    if (c[d] > (1LL << 30)) throw ConfigError("domain.cells", "too many cells along an axis");
    g.cells[d] = static_cast<int>(c[d]);
  }
  g.periodic = {cfg.boolean("domain.periodic.x"), cfg.boolean("domain.periodic.y"),
                cfg.boolean("domain.periodic.z")};
  return g;
}

int minBlockCells(const Config& cfg) {
  // The fluid keeps two ghost layers and needs blocks at least that thick; the DEM alone needs a
  // cell.
  return runMode(cfg) == RunMode::ParticlesOnly ? 1 : 2;
}

Int3 processGridFromConfig(const Config& cfg, int ranks) {
  const auto d = cfg.intVec3("partition.dims");
  return Decomposition::chooseDims(
      ranks, gridFromConfig(cfg),
      {static_cast<int>(d[0]), static_cast<int>(d[1]), static_cast<int>(d[2])}, minBlockCells(cfg));
}

Decomposition decompositionFromConfig(const Comm& world, const Config& cfg) {
  const auto d = cfg.intVec3("partition.dims");
  return Decomposition::uniform(
      world, gridFromConfig(cfg),
      {static_cast<int>(d[0]), static_cast<int>(d[1]), static_cast<int>(d[2])}, minBlockCells(cfg));
}

}  // namespace coloc
