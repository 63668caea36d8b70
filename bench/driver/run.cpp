#include "run.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>

#include "coloc/core/config.hpp"
#include "coloc/core/report.hpp"
#include "coloc/coupling/case_checks.hpp"
#include "coloc/coupling/rebalance.hpp"
#include "coloc/coupling/simulation.hpp"
#include "diagnostics.hpp"

namespace coloc {
namespace {

/// Rank 0 prints a progress line every `interval` seconds: step, simulated time, step rate,
/// estimated time left and the pressure iterations (last, average over the run).
class Progress {
 public:
  Progress(const Comm& comm, double interval, const coupling::Simulation& sim)
      : root_(comm.isRoot()), interval_(interval), steps0_(sim.steps()), time0_(sim.time()) {
    t0_ = last_ = MPI_Wtime();
  }
  void update(coupling::Simulation& sim, long long maxSteps, double endTime) {
    if (!root_ || interval_ <= 0) return;
    const double now = MPI_Wtime();
    if (now - last_ < interval_) return;
    last_ = now;
    const double elapsed = std::max(now - t0_, 1e-300);
    const double done = static_cast<double>(sim.steps() - steps0_);
    const double rate = done / elapsed;
    double left = 0;
    char total[32] = "";
    if (maxSteps > 0) {
      left = static_cast<double>(maxSteps - sim.steps()) / std::max(rate, 1e-300);
      std::snprintf(total, sizeof total, "/%lld", maxSteps);
    } else if (sim.time() > time0_) {
      left = (endTime - sim.time()) / (sim.time() - time0_) * elapsed;
    }
    char pressure[96] = "";
    if (const auto* f = sim.fluid()) {
      const fv::FluidCounters c = f->counters();
      if (c.solves > 0)
        std::snprintf(pressure, sizeof pressure, "  p-iter %lld (avg %.1f)", c.itLast,
                      static_cast<double>(c.itSum) / static_cast<double>(c.solves));
    }
    std::printf("coloc: step %lld%s  t = %.6g s  dt = %.3g s  %.2f steps/s  %.0f s left%s\n",
                sim.steps(), total, sim.time(), sim.lastDt(), rate, std::max(left, 0.0), pressure);
    std::fflush(stdout);
  }

 private:
  bool root_;
  double interval_, t0_, last_;
  long long steps0_;
  double time0_;
};

/// A per-step time series (series.csv): coupling totals, the particles of
/// output.series_particles / output.series_particle_ids, and the bed diagnostics
/// (diagnostics.hpp) on the steps of output.diagnostics_interval and the last step (empty fields
/// in the other rows).
class Series {
 public:
  Series(const Comm& comm, const std::string& path, coupling::Simulation& sim, const Config& cfg)
      : comm_(comm), cfg_(cfg) {
    auto* dem = sim.particles();
    const long long total = dem ? dem->globalCount() : 0;
    const Json& ids = cfg.at("output.series_particle_ids");
    if (!ids.empty()) {
      for (const auto& v : ids) {
        const double x = v.get<double>();
        if (x != std::floor(x) || x < 0 || x >= static_cast<double>(total)) {
          char id[32];
          std::snprintf(id, sizeof id, "%.17g", x);
          throw ConfigError("output.series_particle_ids", "particle id " + std::string(id) +
                                                              " is not one of the ids 0.." +
                                                              std::to_string(total - 1));
        }
        ids_.push_back(static_cast<long long>(x));
      }
    } else {
      for (long long i = 0; i < std::min<long long>(total, cfg.integer("output.series_particles"));
           ++i)
        ids_.push_back(i);
    }
    for (std::size_t c = 0; c < ids_.size(); ++c) column_[ids_[c]] = c;
    diagEvery_ = cfg.integer("output.diagnostics_interval");
    if (diagEvery_ == 0) diagEvery_ = cfg.integer("output.interval_steps");
    if (!comm_.isRoot()) return;
    out_.open(path);
    out_ << "step,time,solid_volume,fluid_accel_l1";
    for (long long id : ids_)
      for (const char* q : {"x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz"})
        out_ << ",p" << id << "_" << q;
    for (const auto& c : bedDiagnosticsColumns()) out_ << "," << c;
    out_ << "\n";
  }
  /// One row; the diagnostics when due or at the end of the run. Returns them when computed.
  std::optional<BedDiagnostics> record(coupling::Simulation& sim) {
    std::vector<double> row(9 * ids_.size(), 0.0);
    if (auto* dem = sim.particles()) {
      const auto& p = dem->particles();
      for (std::size_t i = 0; i < p.nOwned; ++i) {
        const auto it = column_.find(p.id[i]);
        if (it == column_.end()) continue;
        double* r = row.data() + 9 * it->second;
        for (int d = 0; d < 3; ++d) {
          r[d] = p.x[d][i];
          r[3 + d] = p.v[d][i];
          r[6 + d] = p.fExt[d][i];
        }
      }
    }
    comm_.sumInPlace(std::span<double>(row));
    std::optional<BedDiagnostics> diag;
    if ((diagEvery_ > 0 && sim.steps() % diagEvery_ == 0) || sim.finished())
      diag = bedDiagnostics(sim, cfg_);
    if (!comm_.isRoot()) return diag;
    char buf[64];
    out_ << sim.steps();
    for (double v : {sim.time(), sim.depositedSolidVolume(), sim.fluidAccelerationL1()}) {
      std::snprintf(buf, sizeof buf, ",%.17g", v);
      out_ << buf;
    }
    for (double v : row) {
      std::snprintf(buf, sizeof buf, ",%.17g", v);
      out_ << buf;
    }
    if (diag) {
      for (double v : bedDiagnosticsRow(*diag)) {
        std::snprintf(buf, sizeof buf, ",%.17g", v);
        out_ << buf;
      }
    } else {
      out_ << std::string(bedDiagnosticsColumns().size(), ',');
    }
    out_ << "\n";
    return diag;
  }
  void flush() {
    if (out_.is_open()) out_.flush();
  }

 private:
  const Comm& comm_;
  const Config& cfg_;
  std::vector<long long> ids_;
  std::map<long long, std::size_t> column_;
  long long diagEvery_ = 0;
  std::ofstream out_;
};

/// output.snapshot: rank 0 runs bench/scripts/snapshot.py on the run's output (a picture of the
/// last fields and particles, OUT/snapshot.png). Only a warning when it cannot.
void drawSnapshot(const Config& cfg, const std::string& outDir, bool quiet) {
  const OutputOptions o = outputOptionsFromConfig(cfg, outDir);
  if (!cfg.boolean("output.snapshot") || !o.fields || o.intervalSteps <= 0) return;
  namespace fs = std::filesystem;
  const fs::path script = fs::path(COLOC_SOURCE_DIR) / "bench" / "scripts" / "snapshot.py";
  const char* python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const std::string png = (fs::path(outDir) / "snapshot.png").string();
  const std::string cmd = std::string(python) + " " + quote(script.string()) + " " + quote(o.dir) +
                          " --png " + quote(png) + " --report " +
                          quote((fs::path(outDir) / "report.json").string()) +
                          (quiet ? " >/dev/null" : "");
  std::fflush(stdout);
  const int rc = std::system(cmd.c_str());
  if (rc != 0)
    std::fprintf(stderr,
                 "coloc: warning: no snapshot.png (%s exited with status %d); the run's output "
                 "is complete (set output.snapshot=false to skip the picture)\n",
                 script.string().c_str(), rc);
}

}  // namespace

std::string describeKeys() {
  return "Case-file keys (dotted paths; --set takes the same):\n" +
         coupling::caseSchema().describe();
}

int runCase(const Comm& world, const RunOptions& opts) {
  const double t0 = MPI_Wtime();
  const Config cfg = Config::load(world, opts.casePath, opts.overrides, coupling::caseSchema());
  // Whole-case checks and the memory estimate, before anything large is allocated.
  const std::vector<std::string> notes = coupling::checkCase(cfg);
  coupling::checkMemory(world, cfg);
  if (world.isRoot())
    for (const auto& n : notes) std::printf("coloc: note: %s\n", n.c_str());
  const std::string outDir = opts.outDir.empty()
                                 ? (std::filesystem::path("out") / cfg.string("name")).string()
                                 : opts.outDir;
  if (world.isRoot()) makeDirectories(outDir);
  const CheckpointOptions checkpoint = checkpointOptionsFromConfig(cfg, outDir);
  std::unique_ptr<coupling::Simulation> simulation;
  if (opts.restart.empty())
    simulation = std::make_unique<coupling::Simulation>(world, cfg);
  else
    simulation = std::make_unique<coupling::Simulation>(
        cfg, coupling::Simulation::restartLayouts(world, cfg, opts.restart), opts.restart);
  const double setupWall = MPI_Wtime() - t0;
  const long long particleCount =
      simulation->particles() ? simulation->particles()->globalCount() : 0;  // collective
  if (world.isRoot() && !opts.quiet) {
    const auto& dec = simulation->decomposition();
    std::printf(
        "coloc: case '%s', mode %s, %d rank(s) as %dx%dx%d, %lld cells, %lld particles, "
        "set-up %.2f s\n",
        cfg.string("name").c_str(), runModeName(simulation->mode()), dec.size(), dec.dims()[0],
        dec.dims()[1], dec.dims()[2], static_cast<long long>(dec.grid().cellCount()), particleCount,
        setupWall);
    if (!opts.restart.empty())
      std::printf("coloc: restarted from %s at step %lld, t = %.9g s\n", opts.restart.c_str(),
                  simulation->steps(), simulation->time());
  }
  Progress progress(world, opts.quiet ? 0.0 : cfg.number("run.progress_interval_s"), *simulation);
  Series series(world, (std::filesystem::path(outDir) / "series.csv").string(), *simulation, cfg);
  std::optional<BedDiagnostics> lastDiagnostics;
  OutputWriter output(simulation->decomposition(), outputOptionsFromConfig(cfg, outDir));
  simulation->writeOutput(output);
  simulation->beginRun();
  const double tLoop = MPI_Wtime();
  long long rebalances = 0;
  try {
    while (!simulation->finished()) {
      simulation->step();
      simulation->writeOutput(output);
      if (auto d = series.record(*simulation)) lastDiagnostics = std::move(d);
      if (checkpoint.due(simulation->steps()))
        simulation->writeCheckpoint(checkpoint.pathAt(simulation->steps()));
      if (coupling::rebalanceDue(cfg, simulation->steps())) {
        const auto plan = coupling::planRebalance(*simulation, cfg);
        if (plan.layouts) {
          simulation = coupling::applyRebalance(
              std::move(simulation), cfg, *plan.layouts,
              (std::filesystem::path(outDir) / "rebalance.tmp.h5").string());
          output.rebind(simulation->decomposition());
          ++rebalances;
          if (world.isRoot() && !opts.quiet) {
            const auto& d = simulation->decomposition().dims();
            std::printf("coloc: step %lld: re-balanced onto %dx%dx%d blocks, modelled imbalance "
                        "%.3f -> %.3f\n",
                        simulation->steps(), d[0], d[1], d[2], plan.currentImbalance,
                        plan.newImbalance);
          }
        }
      }
      progress.update(*simulation, cfg.integer("run.steps"), cfg.number("run.end_time"));
    }
    // The final state, unless the last step wrote it already.
    if (checkpoint.intervalSteps > 0 && !checkpoint.due(simulation->steps()))
      simulation->writeCheckpoint(checkpoint.pathAt(simulation->steps()));
  } catch (const Error& e) {
    // A failure inside the time loop reaches every rank here together (the solvers raise their
    // checks collectively). Keep the state for inspection, say what happened, exit non-zero.
    if (!simulation) {  // failed while moving onto new blocks: no state left in memory
      if (world.isRoot()) std::fprintf(stderr, "coloc: error: re-balancing failed: %s\n", e.what());
      return kRunFailedStatus;
    }
    char when[160];
    std::snprintf(when, sizeof when, "the run failed in step %lld (from t = %.9g s)",
                  simulation->steps() + 1, simulation->time());
    const std::string message = e.what();
    std::string saved, saveError;
    if (checkpoint.onFailure) {
      const std::string path = failedCheckpointPath(checkpoint.pathAt(simulation->steps() + 1));
      try {
        simulation->writeCheckpoint(path, "failed: " + std::string(when) + ": " + message);
        saved = path;
      } catch (const Error& e2) {
        saveError = e2.what();
      }
    }
    series.flush();
    if (world.isRoot()) {
      std::fprintf(stderr, "coloc: error: %s: %s\n", when, message.c_str());
      if (!saved.empty())
        std::fprintf(stderr,
                     "coloc: the state at the failure is in %s (status 'failed'; not "
                     "restartable)%s%s\n",
                     saved.c_str(), checkpoint.intervalSteps > 0 ? "; last good checkpoint: " : "",
                     checkpoint.intervalSteps > 0 ? checkpoint.path.c_str() : "");
      if (!saveError.empty())
        std::fprintf(stderr, "coloc: could not write the failed state: %s\n", saveError.c_str());
    }
    return kRunFailedStatus;
  }
  const double loopWall = MPI_Wtime() - tLoop;

  Report report(opts.casePath, cfg.json());
  report.merge(simulation->report(loopWall));
  report.set("run.setup_s", world.max(setupWall));
  report.set("partition.rebalances", rebalances);
  report.set("run.notes", notes);
  report.set("bed", bedDiagnosticsJson(lastDiagnostics ? *lastDiagnostics
                                                       : bedDiagnostics(*simulation, cfg)));
  report.set("run.total_wall_s", world.max(MPI_Wtime() - t0));
  report.addMemory(world);
  const std::string path = report.write(world, outDir);
  if (world.isRoot()) {
    const auto& j = report.json();
    std::printf(
        "coloc: %lld steps (%lld DEM sub-steps), t = %.6g s, %.3f s wall, "
        "%.3g cell-steps/s, %.3g particle-steps/s, inter-physics %.3f%% of the step\n",
        j["run"]["steps"].get<long long>(), j["run"]["dem_substeps"].get<long long>(),
        j["run"]["sim_time"].get<double>(), j["run"]["wall_s"].get<double>(),
        j["throughput"]["cell_steps_per_s"].get<double>(),
        j["throughput"]["particle_steps_per_s"].get<double>(),
        100.0 * j["fractions"]["inter_physics"].get<double>());
    std::printf("coloc: report written to %s\n", path.c_str());
  }
  if (world.isRoot()) drawSnapshot(cfg, outDir, opts.quiet);
  return 0;
}

}  // namespace coloc
