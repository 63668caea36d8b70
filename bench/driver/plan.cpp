// `coloc plan`: the layouts of every strategy for rank counts that are not run, their work and
// their traffic per step (coupling/plan.hpp), in one process.
#include "plan.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "coloc/core/config.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/files.hpp"
#include "coloc/core/report.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/coupling/plan.hpp"
#include "coloc/coupling/simulation.hpp"

namespace coloc {

std::vector<int> parseRankList(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t pos = 0;
    long long v = 0;
    try {
      v = std::stoll(item, &pos);
    } catch (const std::exception&) {
      pos = 0;
    }
    if (pos != item.size() || v < 1 || v > (1 << 24))
      throw Error("--ranks: '" + item + "' is not a rank count (comma-separated integers >= 1)");
    out.push_back(static_cast<int>(v));
  }
  if (out.empty()) throw Error("--ranks: give at least one rank count, e.g. --ranks 28,56,1024");
  return out;
}

int planCase(const PlanOptions& opts) {
  const double t0 = MPI_Wtime();
  const Comm self(MPI_COMM_SELF);
  const Config cfg = Config::load(self, opts.casePath, opts.overrides, coupling::caseSchema());
  std::vector<const PartitionStrategy*> strategies;
  for (const auto& s : opts.strategies)
    strategies.push_back(&PartitionStrategy::named(s, "--strategy"));
  if (strategies.empty())
    for (const PartitionStrategy* s : PartitionStrategy::all())
      if (s->plannedByDefault()) strategies.push_back(s);
  const auto ranks = parseRankList(opts.ranks);
  const std::string outDir =
      opts.outDir.empty() ? (std::filesystem::path("out") / cfg.string("name") / "plan").string()
                          : opts.outDir;
  makeDirectories(outDir);
  // Regular files in the folder, never written through a link (coloc/core/files.hpp): checked
  // before the work, written whole at the end.
  const std::string csvPath = (std::filesystem::path(outDir) / "plan.csv").string();
  const std::string jsonPath = (std::filesystem::path(outDir) / "plan.json").string();
  for (const std::string& path : {csvPath, jsonPath})
    if (const std::string why = writeTargetProblem(path); !why.empty()) throw IoError(why);
  const coupling::PlanCase pc = coupling::planCase(cfg);
  const double tSetup = MPI_Wtime() - t0;

  Json layouts = Json::array();
  std::ostringstream csv;
  csv << "strategy,ranks,rank,cells,particles,proxies,ghost_cells,dem_ghosts,cost";
  for (const auto n : kTrafficNames) csv << "," << n << "_bytes," << n << "_messages";
  csv << "\n";
  std::printf("coloc plan: %s, %lld cells, %lld particles, mode %s (set-up %.2f s)\n",
              cfg.string("name").c_str(), pc.grid.cellCount(),
              static_cast<long long>(pc.particles.x[0].size()), runModeName(pc.mode), tSetup);
  std::printf("%-12s %6s %-10s %-10s %9s %12s %12s %12s %12s %12s\n", "strategy", "ranks", "fluid",
              "dem", "imbalance", "max cells", "max parts", "halo MB/st", "ghost MB/st",
              "inter MB/st");
  for (const PartitionStrategy* s : strategies)
    for (const int n : ranks) {
      const std::string strategy(s->name());
      const coupling::LayoutPlan L = coupling::planLayout(pc, *s, n);
      Json j = {{"strategy", strategy}, {"ranks", n}};
      if (!L.error.empty()) {
        j["error"] = L.error;
        layouts.push_back(j);
        std::printf("%-12s %6d  refused: %s\n", strategy.c_str(), n, L.error.c_str());
        continue;
      }
      const auto dims = [](const Blocks& b) {
        return Json::array({b.dims[0], b.dims[1], b.dims[2]});
      };
      const bool tiled = !L.boxes.empty();
      if (tiled) {  // one box per rank, no process grid: [lo x, y, z, hi x, y, z] a rank
        Json boxes = Json::array();
        for (const auto& b : L.boxes)
          boxes.push_back(Json::array({b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]}));
        j["boxes"] = boxes;
        j["modelled_imbalance"] = L.modelledImbalance;
        j["imbalance_floor"] = L.imbalanceFloor;
      } else {
        j["fluid_dims"] = dims(L.fluid);
        j["particle_dims"] = dims(L.particles);
        j["fluid_cuts"] = {L.fluid.cuts[0], L.fluid.cuts[1], L.fluid.cuts[2]};
        j["particle_cuts"] = {L.particles.cuts[0], L.particles.cuts[1], L.particles.cuts[2]};
      }
      j["dem_substeps_per_step"] = L.substeps;
      j["imbalance"] = L.imbalance;
      Json per = Json::object();
      std::vector<long long> cells, parts, prox, gc, dg;
      std::vector<double> cost;
      std::array<std::vector<long long>, kTrafficNames.size()> tb, tm;
      std::array<long long, kTrafficNames.size()> sumB{}, sumM{};
      long long maxCells = 0, maxParts = 0;
      for (int r = 0; r < n; ++r) {
        const auto& R = L.rank[static_cast<std::size_t>(r)];
        cells.push_back(R.cells);
        parts.push_back(R.particles);
        prox.push_back(R.proxies);
        gc.push_back(R.ghostCells);
        dg.push_back(R.demGhosts);
        cost.push_back(R.cost);
        maxCells = std::max(maxCells, R.cells);
        maxParts = std::max(maxParts, R.particles);
        csv << strategy << "," << n << "," << r << "," << R.cells << "," << R.particles << ","
            << R.proxies << "," << R.ghostCells << "," << R.demGhosts << "," << R.cost;
        for (std::size_t t = 0; t < kTrafficNames.size(); ++t) {
          tb[t].push_back(R.perStep[t].bytes);
          tm[t].push_back(R.perStep[t].messages);
          sumB[t] += R.perStep[t].bytes;
          sumM[t] += R.perStep[t].messages;
          csv << "," << R.perStep[t].bytes << "," << R.perStep[t].messages;
        }
        csv << "\n";
      }
      per["cells"] = cells;
      per["particles"] = parts;
      per["proxies"] = prox;
      per["ghost_cells"] = gc;
      per["dem_ghosts"] = dg;
      per["cost"] = cost;
      if (tiled) {
        std::vector<long long> nb;
        for (const auto& R : L.rank) nb.push_back(R.haloNeighbours);
        per["halo_neighbours"] = nb;
      }
      Json kinds = Json::object(), totals = Json::object();
      for (std::size_t t = 0; t < kTrafficNames.size(); ++t) {
        const std::string name(kTrafficNames[t]);
        kinds[name] = {{"bytes", tb[t]}, {"messages", tm[t]}};
        totals[name] = {{"bytes", sumB[t]}, {"messages", sumM[t]}};
      }
      per["per_step"] = kinds;
      j["per_rank"] = per;
      j["per_step_total"] = totals;
      layouts.push_back(j);
      const auto mb = [](long long b) { return static_cast<double>(b) / 1e6; };
      const std::size_t FH = 0, CH = 1, DG = 2, DS = 4, PX = 5;
      char fd[32], dd[32];
      std::snprintf(fd, sizeof fd, "%dx%dx%d", L.fluid.dims[0], L.fluid.dims[1], L.fluid.dims[2]);
      std::snprintf(dd, sizeof dd, "%dx%dx%d", L.particles.dims[0], L.particles.dims[1],
                    L.particles.dims[2]);
      if (tiled) {
        std::snprintf(fd, sizeof fd, "boxes");
        std::snprintf(dd, sizeof dd, "boxes");
      }
      std::printf("%-12s %6d %-10s %-10s %9.3f %12lld %12lld %12.3f %12.3f %12.3f\n",
                  strategy.c_str(), n, fd, dd, L.imbalance, maxCells, maxParts,
                  mb(sumB[FH] + sumB[CH]), mb(sumB[DG]), mb(sumB[DS] + sumB[PX]));
      std::fflush(stdout);
    }
  Json plan = {{"case", cfg.string("name")},
               {"mode", runModeName(pc.mode)},
               {"cells", {pc.grid.cells[0], pc.grid.cells[1], pc.grid.cells[2]}},
               {"particles", static_cast<long long>(pc.particles.x[0].size())},
               {"interaction_range", pc.particles.range},
               {"cost_per_cell", cfg.number("partition.cost.cell")},
               {"cost_per_particle", cfg.number("partition.cost.particle")},
               {"layouts", layouts}};
  plan["wall_s"] = MPI_Wtime() - t0;
  plan["peak_rss_bytes"] = peakRssBytes();
  writeFileWhole(csvPath, csv.str());
  writeFileWhole(jsonPath, plan.dump(1) + "\n");
  std::printf("coloc plan: wrote %s/plan.json and plan.csv (%.2f s, peak RSS %.2f GiB)\n",
              outDir.c_str(), MPI_Wtime() - t0,
              static_cast<double>(peakRssBytes()) / (1024.0 * 1024.0 * 1024.0));
  return 0;
}

}  // namespace coloc
