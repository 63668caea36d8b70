#include "run.hpp"

#include <cstdio>
#include <filesystem>

#include "coloc/core/config.hpp"
#include "coloc/core/report.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/partition/field.hpp"
#include "coloc/partition/halo.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc {
namespace {

Schema caseSchema() {
  Schema s;
  declareRunConfig(s);
  declareDomainConfig(s);
  return s;
}

}  // namespace

std::string describeKeys() { return "Case-file keys (dotted paths; --set takes the same):\n" + caseSchema().describe(); }

int runCase(const Comm& world, const RunOptions& opts) {
  const double t0 = MPI_Wtime();
  Timers timers;
  timers.start(Phase::Setup);
  const Config cfg = Config::load(world, opts.casePath, opts.overrides, caseSchema());
  const Decomposition dec = decompositionFromConfig(world, cfg);
  const std::string outDir =
      opts.outDir.empty() ? (std::filesystem::path("out") / cfg.string("name")).string() : opts.outDir;

  // Until the solvers run here, the job reports the decomposition and one halo exchange of a
  // cell field and of the three face components: what every step will move.
  CellField cell(cellLayout(dec, 1));
  HaloPlan cellHalo(dec, cell.layout());
  timers.stop(Phase::Setup);
  timers.start(Phase::FluidHalo);
  cellHalo.gather(cell, &timers, Exchange::IntraPhysics);
  timers.stop(Phase::FluidHalo);

  const auto cells = dec.ownedCellCount();
  const auto cellsMM = dec.comm().minMaxAvg(static_cast<double>(cells));
  Report report(opts.casePath, cfg.json());
  report.set("mpi.ranks", dec.size());
  report.set("mpi.dims", Json::array({dec.dims()[0], dec.dims()[1], dec.dims()[2]}));
  report.set("run.mode", runModeName(runMode(cfg)));
  report.set("run.steps", 0);
  report.set("run.dem_substeps", 0);
  report.set("run.sim_time", 0.0);
  report.set("decomposition.cells_total", dec.grid().cellCount());
  report.set("decomposition.cells_per_rank", {{"min", cellsMM.min}, {"avg", cellsMM.avg}, {"max", cellsMM.max}});
  report.set("decomposition.halo_bytes_per_field", dec.comm().sum(cellHalo.bytesPerGather()));
  const double wall = MPI_Wtime() - t0;
  report.merge(timers.report(dec.comm(), wall));
  report.set("run.wall_s", dec.comm().max(wall));
  report.addMemory(dec.comm());
  const std::string path = report.write(dec.comm(), outDir);
  if (world.isRoot()) {
    std::printf("coloc: case '%s' on %d rank(s), process grid %dx%dx%d, %lld cells (%.0f-%.0f per rank)\n",
                cfg.string("name").c_str(), dec.size(), dec.dims()[0], dec.dims()[1], dec.dims()[2],
                static_cast<long long>(dec.grid().cellCount()), cellsMM.min, cellsMM.max);
    std::printf("coloc: report written to %s\n", path.c_str());
  }
  return 0;
}

}  // namespace coloc
