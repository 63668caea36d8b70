// `coloc run` (run.hpp): the phases of a run, each agreed by every rank (coloc/core/failure.hpp),
// in the order runCase() calls them: the output folders, the set-up, the step loop, the final
// report. The time series is series.hpp, the stop signals stop_signals.hpp, the picture at the
// end snapshot.hpp.
#include "run.hpp"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include "coloc/core/config.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"
#include "coloc/core/fault.hpp"
#include "coloc/core/files.hpp"
#include "coloc/core/provenance.hpp"
#include "coloc/core/report.hpp"
#include "coloc/coupling/case_checks.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/coupling/rebalance.hpp"
#include "coloc/coupling/simulation.hpp"
#include "coloc/fv/library_version.hpp"
#include "coloc/io/library_version.hpp"
#include "diagnostics.hpp"
#include "phase.hpp"
#include "progress.hpp"
#include "restart_account.hpp"
#include "run_folder.hpp"
#include "run_log.hpp"
#include "series.hpp"
#include "snapshot.hpp"
#include "stop_signals.hpp"
#include "summary.hpp"

namespace coloc {
namespace {

/// What libraryAborted() needs of the run in progress (set by runCase while it runs; the
/// abort comes from inside a library, with no way back to runCase's frame).
struct LastWords {
  const Comm* world = nullptr;
  std::string casePath, outDir;
  const Json* config = nullptr;
  const Json* provenance = nullptr;
};
LastWords lastWords;

}  // namespace

void libraryAborted() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  std::string msg = std::string(kOutOfMemory) +
                    "? hypre stopped the job with MPI_Abort(-1), as it does when an allocation "
                    "fails";
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY)
    msg += " (address-space limit RLIMIT_AS, ulimit -v: " +
           coupling::bytesText(static_cast<double>(as.rlim_cur)) + ")";
  msg = fmt::format("rank {}: {}", rank, msg);
  std::fprintf(stderr, "coloc: error: %s; stopping every rank (exit status %d)\n", msg.c_str(),
               kRunFailedStatus);
  std::fflush(stderr);
  // The report from this rank alone (the others cannot be reached in order any more): through a
  // .tmp of its own and a rename, as every report.
  if (lastWords.world && lastWords.config && !lastWords.outDir.empty()) {
    try {
      Report report(lastWords.casePath, *lastWords.config);
      report.set("status", "failed");
      report.set("exit_code", kRunFailedStatus);
      report.set("error", msg);
      report.set("out_of_memory", true);
      if (lastWords.provenance) report.set("provenance", *lastWords.provenance);
      const std::filesystem::path dir(lastWords.outDir);
      const std::string tmp = (dir / ("report.rank" + std::to_string(rank) + ".json.tmp")).string();
      const std::string text = report.json().dump(2) + "\n";
      const int fd = createFresh(tmp);  // never through a link (coloc/core/files.hpp)
      const bool whole = writeAll(fd, text) == 0;
      ::close(fd);
      if (whole)
        (void)publishFile(tmp, (dir / "report.json").string());
      else
        ::unlink(tmp.c_str());
    } catch (...) {
      // nothing more can be done here: the message above stands
    }
  }
  PMPI_Abort(MPI_COMM_WORLD, kRunFailedStatus);
  std::_Exit(kRunFailedStatus);
}

std::string describeKeys() {
  return "Case-file keys (dotted paths; --set takes the same):\n" +
         coupling::caseSchema().describe();
}

namespace {

/// One `coloc run`, phase by phase (runCase() calls them in order). The constructor reads the
/// case (an input error found there escapes as coloc::Error, the same on every rank); every
/// phase after it returns 0 to go on, or the exit status it agreed on, its error printed and
/// report.json written where an output folder exists.
class Run {
 public:
  Run(const Comm& world, const RunOptions& opts);
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;

  int prepareFolders();
  void openLog();
  void sayEarlierKept();
  int setUp();
  int stepLoop();
  int finish(std::optional<SnapshotJob>& snapshot);

 private:
  /// The parts of a step, for the message of a failure (the verdict's `where`).
  enum Part { kStep = 0, kOutput, kSeries, kCheckpoint, kRebalance };

  void step(int& where);
  int failInLoop(const FailureChannel::Verdict& v);
  int stopBySignal(int sig);
  void printSummary(const std::string& reportPath);
  std::string writeReport(const char* status, int code, const std::string& error,
                          const std::string& state, int sig);
  void say(const FailureChannel::Verdict& v, const std::string& before) {
    log_.err("coloc: error: {}{}\n", before, v.message);
  }

  // In the order a run makes them (and frees them in reverse, as runCase's locals once did).
  const double t0_;
  const Comm& world_;
  const RunOptions& opts_;
  // Phase agreements go through a communicator of their own (coloc/core/failure.hpp).
  const FailureChannel channel_;
  const Config cfg_;
  std::vector<std::string> notes_;
  // Rank 0's messages, also into OUT/log.txt once the folder is ready (the lines before kept).
  RunLog log_;
  Json prov_;  // where the run comes from: report.json's "provenance"
  std::string outDir_;
  CheckpointOptions checkpoint_;
  OutputOptions outputOptions_;
  bool root_;
  // For libraryAborted(), while this run is in progress.
  struct ClearLastWords {
    ~ClearLastWords() { lastWords = {}; }
  } clearLastWords_;
  RunFolders folders_;
  FolderLocks locks_;
  std::vector<std::string> earlierFiles_;  // rank 0: an earlier run's files, for --overwrite
  bool keepEarlier_ = false;               // every rank: they stay until the set-up has passed
  bool logOpen_ = false;                   // rank 0: OUT/log.txt is open

  // What report.json says of the run, however it ends.
  std::unique_ptr<coupling::Simulation> simulation_;
  long long rebalances_ = 0;
  double setupWall_ = 0, tLoop_ = 0;
  Json written_;                                   // the last report written
  Json restartReport_;                             // a restart: what came from where
  long long unconvergedWarned_ = 0;                // pressure solves above tol, warned of
  std::optional<BedDiagnostics> lastDiagnostics_;  // of the last series row that had them

  // A progress row: rank 0's clock asks for one at the end of the set-up or a step (`request_`,
  // carried by its agreement); every rank computes it on the next step, and on the last.
  std::optional<Progress> progress_;
  int request_ = 0;
  bool rowDue_ = false;
  std::optional<Series> series_;
  std::optional<OutputWriter> output_;

  // The keys the loop needs, parsed once (no string look-ups inside the loop).
  long long rebalanceEvery_ = 0;
  bool rebalanceThroughFile_ = false;
  std::string rebalanceScratch_;
  long long pressureMaxIter_ = 0;
  double pressureTol_ = 0;
  std::string lastCheckpoint_;
};

Run::Run(const Comm& world, const RunOptions& opts)
    : t0_(MPI_Wtime()),
      world_(world),
      opts_(opts),
      channel_(world),
      cfg_(Config::load(world, opts.casePath, opts.overrides, coupling::caseSchema())),
      // Whole-case checks and (below) the memory estimate, before anything large is allocated.
      notes_(coupling::checkCase(cfg_)),
      log_(world.isRoot()),
      root_(world.isRoot()) {
  coupling::checkMemory(world, cfg_);
  for (const auto& n : notes_) log_.out("coloc: note: {}\n", n);
  setFailureWait(cfg_.number("run.failure_wait_s"));
  // Where the run comes from (collective).
  prov_ = provenance(world, opts.commandLine);
  prov_["hypre_version"] = fv::hypreVersion();
  prov_["hdf5_version"] = hdf5Version();
  outDir_ = opts.outDir.empty() ? (std::filesystem::path("out") / cfg_.string("name")).string()
                                : opts.outDir;
  checkpoint_ = checkpointOptionsFromConfig(cfg_, outDir_);
  outputOptions_ = outputOptionsFromConfig(cfg_, outDir_);
  lastWords = {&world, opts.casePath, outDir_, &cfg_.json(), &prov_};
  folders_ = {outDir_, outputOptions_.dir, cfg_.string("output.checkpoint_file")};
}

/// 1. The output folders (rank 0): made; locked against a second run for as long as this one
/// lasts; the checkpoint kept inside them and off the --restart file; an earlier run's files
/// refused (or removed with --overwrite); what a previous run left there that would mislead
/// removed. A --restart that is no regular file (a FIFO would block the read), and a file the run
/// would write that is not one (coloc/core/files.hpp), are refused before anything is made. Then
/// the log file opens, unless --overwrite keeps an earlier run's files until the set-up passed.
int Run::prepareFolders() {
  std::vector<std::string>& earlierFiles = earlierFiles_;
  auto v = phase(channel_, kInputErrorStatus, [&] {
    onRoot(world_, [&] {
      // Every file the run writes: a name it can write, and nothing there that is not a regular
      // file (coloc/core/files.hpp); before any folder is made.
      checkWritePaths(folders_);
      if (opts_.restart.empty()) return;
      if (const std::string why = notRegularFile(opts_.restart); !why.empty())
        throw ConfigError("--restart",
                          "'" + opts_.restart + (why == "no such file" ? "': " : "' ") + why);
    });
  });
  if (!v.failed())
    v = phase(channel_, kIoErrorStatus, [&] {
      onRoot(world_, [&] {
        makeDirectories(outDir_);
        makeDirectories(folders_.dataDir);
      });
    });
  if (!v.failed())
    v = phase(channel_, kInputErrorStatus, [&] {
      onRoot(world_, [&] {
        locks_.lock(outDir_, "--out", opts_.casePath);
        std::error_code ec;
        if (!std::filesystem::equivalent(outDir_, folders_.dataDir, ec))
          locks_.lock(folders_.dataDir, "output.dir", opts_.casePath);
        checkRunFiles(folders_, opts_.restart);
        // Two runs never mix in one folder: an earlier run's files refuse the run, unless it
        // continues that run (--restart of a checkpoint there) or replaces it (--overwrite).
        if (!restartInFolders(folders_, opts_.restart)) {
          earlierFiles = previousRunFiles(folders_);
          if (!opts_.overwrite) refuseMixedRuns(folders_, earlierFiles);
        }
      });
    });
  if (!v.failed())
    v = phase(channel_, kIoErrorStatus, [&] {
      // --overwrite: the earlier run's files stay until this run is set up (setUp)
      keepEarlier_ = world_.broadcast(std::string(earlierFiles.empty() ? "" : "1")) == "1";
      if (keepEarlier_) lastWords.outDir.clear();  // (no report over the earlier run's, either)
      if (!root_) return;
      removeStaleFiles(folders_);
      fault::point("outdir", 0);
      if (!keepEarlier_) openLog();
    });
  if (v.failed()) {
    say(v, "");
    if (keepEarlier_) sayEarlierKept();
    return v.code;
  }
  return 0;
}

void Run::sayEarlierKept() {
  if (root_)
    log_.err(
        "coloc: the earlier run's files in '{}' are left as they were (--overwrite removes them "
        "only once the new run is set up); no report written\n",
        outDir_);
}

void Run::openLog() {
  log_.open((std::filesystem::path(outDir_) / "log.txt").string(),
            restartInFolders(folders_, opts_.restart), logHeader(prov_, opts_.casePath, outDir_));
  logOpen_ = true;
}

/// report.json, however the run ends (collective; a failure to write it is printed, the exit
/// status stays that of the run). Returns its path, empty when it could not be written.
std::string Run::writeReport(const char* status, int code, const std::string& error,
                             const std::string& state, int sig) {
  std::string path;
  const auto r = phase(channel_, kIoErrorStatus, [&] {
    Report report(opts_.casePath, cfg_.json());
    if (simulation_) report.merge(simulation_->report(tLoop_ > 0 ? MPI_Wtime() - tLoop_ : 0.0));
    report.set("status", status);
    report.set("exit_code", code);
    report.set("provenance", prov_);
    if (simulation_) report.set("figure_of_merit", figureOfMerit(report.json()));
    if (!error.empty()) report.set("error", error);
    if (outOfMemory(error)) report.set("out_of_memory", true);
    if (!restartReport_.is_null()) report.set("restart", restartReport_);
    if (!state.empty()) report.set("checkpoint", state);
    if (sig != 0) report.set("signal", signalName(sig));
    report.set("run.setup_s", world_.max(setupWall_));
    report.set("partition.rebalances", rebalances_);
    report.set("run.notes", notes_);
    // The bed as it ends: computed now at a good end, the last computed otherwise.
    if (lastDiagnostics_)
      report.set("bed", bedDiagnosticsJson(*lastDiagnostics_));
    else if (simulation_ && code == 0)
      report.set("bed", bedDiagnosticsJson(bedDiagnostics(*simulation_, cfg_)));
    report.set("run.total_wall_s", world_.max(MPI_Wtime() - t0_));
    report.addMemory(world_);
    fault::point("report", simulation_ ? simulation_->steps() : 0);
    path = report.write(world_, outDir_);
    written_ = report.json();
  });
  if (r.failed() && root_) log_.err("coloc: error: could not write the report: {}\n", r.message);
  return r.failed() ? std::string() : path;
}

/// 2. Set-up: the physics (fresh, or restarted from --restart), the series, the output of
/// step 0, the progress table's header and first row.
int Run::setUp() {
  // a. The physics: what an input can still refuse (particles that do not fit, a restart file
  // that does not match). An earlier run that --overwrite replaces is untouched until it passed.
  auto v = phase(channel_, kInputErrorStatus, [&] {
    if (opts_.restart.empty())
      simulation_ = std::make_unique<coupling::Simulation>(world_, cfg_);
    else
      simulation_ = std::make_unique<coupling::Simulation>(
          cfg_, coupling::Simulation::restartLayouts(world_, cfg_, opts_.restart), opts_.restart);
    setupWall_ = MPI_Wtime() - t0_;
    const long long particleCount =
        simulation_->particles() ? simulation_->particles()->globalCount() : 0;  // collective
    if (root_) {
      // With --quiet these lines go to the log only.
      const auto& dec = simulation_->decomposition();
      const std::string caseLine = fmt::format(
          "coloc: case '{}', mode {}, {} rank(s) as {}, {} cells, {} particles, "
          "set-up {:.2f} s\n",
          cfg_.string("name"), runModeName(simulation_->mode()), dec.size(), dec.shape(),
          static_cast<long long>(dec.grid().cellCount()), particleCount, setupWall_);
      const std::string restartLine =
          opts_.restart.empty()
              ? std::string()
              : fmt::format("coloc: restarted from {} at step {}, t = {:.9g} s\n", opts_.restart,
                            simulation_->steps(), simulation_->time());
      if (opts_.quiet)
        log_.file("{}{}", caseLine, restartLine);
      else
        log_.out("{}{}", caseLine, restartLine);
    }
    if (!opts_.restart.empty()) {
      restartReport_ = accountRestart(world_, opts_.restart, cfg_, log_);
      refuseEmptyRestart(cfg_, opts_.restart, simulation_->steps(), simulation_->time());
    }
  });
  if (v.failed() && keepEarlier_) {
    say(v, "");
    sayEarlierKept();
    return v.code;
  }
  // b. The run has started: the earlier run's files go (--overwrite), and the previous report of
  // a run continued in place; the log opens.
  if (!v.failed())
    v = phase(channel_, kIoErrorStatus, [&] {
      lastWords.outDir = outDir_;
      if (!root_) return;
      removeRunFiles(earlierFiles_);
      earlierFiles_.clear();
      removePreviousReport(folders_);
      if (!logOpen_) openLog();
    });
  // c. What the run writes from its start: the series, the output of step 0, the progress table.
  if (!v.failed())
    v = phase(
        channel_, kInputErrorStatus,
        [&] {
          progress_.emplace(world_, cfg_,
                            opts_.quiet ? 0.0 : cfg_.number("run.progress_interval_s"), log_);
          series_.emplace(world_, (std::filesystem::path(outDir_) / "series.csv").string(),
                          *simulation_, cfg_);
          output_.emplace(simulation_->decomposition(), outputOptions_);
          simulation_->writeOutput(*output_);
          progress_->start(*simulation_);  // the header and the first row
          request_ = progress_->request();
        },
        nullptr, &request_);
  if (v.failed()) {
    say(v, "");
    writeReport("failed", v.code, v.message, "", 0);
    return v.code;
  }
  rowDue_ = v.request != 0;
  return 0;
}

/// 3. The time loop: one agreement per step, after the step and its output, series, checkpoint
/// and re-balance; it carries the stop signals too.
int Run::stepLoop() {
  rebalanceEvery_ = coupling::rebalanceInterval(cfg_);
  rebalanceThroughFile_ = cfg_.string("partition.rebalance_move") == "file";
  rebalanceScratch_ = (std::filesystem::path(outDir_) / "rebalance.tmp.h5").string();
  pressureMaxIter_ = cfg_.integer("fluid.pressure.max_iter");
  pressureTol_ = cfg_.number("fluid.pressure.tol");
  simulation_->beginRun();
  tLoop_ = MPI_Wtime();
  while (!simulation_->finished()) {
    int where = kStep;
    const auto v = phase(
        channel_, kRunFailedStatus, [&] { step(where); }, &where, &request_);
    rowDue_ = v.request != 0;
    if (v.failed()) return failInLoop(v);
    if (v.signal != 0 && !simulation_->finished()) return stopBySignal(v.signal);
  }
  return 0;
}

/// One step of the loop and what follows it; `where` says which part is running.
void Run::step(int& where) {
  where = kStep;
  simulation_->step();
  where = kOutput;
  simulation_->writeOutput(*output_);
  where = kSeries;
  if (auto d = series_->record(*simulation_)) lastDiagnostics_ = std::move(d);
  if (checkpoint_.due(simulation_->steps())) {
    where = kCheckpoint;
    if (root_) series_->sync();
    simulation_->writeCheckpoint(checkpoint_.pathAt(simulation_->steps()));
    lastCheckpoint_ = checkpoint_.pathAt(simulation_->steps());
  }
  if (coupling::rebalanceDue(rebalanceEvery_, simulation_->steps())) {
    where = kRebalance;
    const auto plan = coupling::planRebalance(*simulation_, cfg_);
    if (plan.layouts) {
      simulation_ = rebalanceThroughFile_
                        ? coupling::applyRebalanceThroughFile(std::move(simulation_), cfg_,
                                                              *plan.layouts, rebalanceScratch_)
                        : coupling::applyRebalance(std::move(simulation_), cfg_, *plan.layouts);
      output_->rebind(simulation_->decomposition());
      ++rebalances_;
      if (root_ && !opts_.quiet) {
        log_.out("coloc: step {}: re-balanced onto {}, modelled imbalance {:.3f} -> {:.3f}\n",
                 simulation_->steps(), simulation_->decomposition().shape(), plan.currentImbalance,
                 plan.newImbalance);
      }
    }
  }
  progress_->row(*simulation_, rowDue_ || simulation_->finished());
  request_ = progress_->request();
  if (root_ && simulation_->fluid()) {
    // The same count on every rank (hypre's norms are global); printed once.
    const fv::FluidCounters c = simulation_->fluid()->counters();
    if (c.unconverged > 0 && unconvergedWarned_ == 0)
      log_.err(
          "coloc: warning: step {}: the pressure solve did not converge "
          "(residual {:.3g} of the flux scale after {} iterations, "
          "fluid.pressure.max_iter = {}, tol = {:g}); counted in report.json "
          "fluid.unconverged_solves (fluid.pressure.on_no_convergence = error "
          "stops the run)\n",
          simulation_->steps(), c.resLast, c.itLast, pressureMaxIter_, pressureTol_);
    unconvergedWarned_ = c.unconverged;
  }
  // Rank 0's series error, after every collective of the step: agreed cleanly.
  if (root_ && !series_->error().empty()) {
    where = kSeries;
    throw IoError(series_->error());
  }
}

/// A step (or what follows it) failed on some rank: what failed where and when, the state kept
/// for inspection where it can be, the report. Returns the agreed exit status.
int Run::failInLoop(const FailureChannel::Verdict& v) {
  static const char* const kPartName[] = {"the step", "writing the output", "writing series.csv",
                                          "writing the checkpoint", "re-balancing"};
  if (!simulation_) {  // failed while moving onto new blocks: no state left in memory
    say(v, "re-balancing failed: ");
    writeReport("failed", v.code, "re-balancing failed: " + v.message, "", 0);
    return v.code;
  }
  const std::string when =
      v.where == kStep
          ? fmt::format("the run failed in step {} (from t = {:.9g} s)", simulation_->steps() + 1,
                        simulation_->time())
          : fmt::format("the run failed after step {} (t = {:.9g} s), {}", simulation_->steps(),
                        simulation_->time(), kPartName[std::clamp(v.where, 0, 4)]);
  // The state at a failure of the physics is kept for inspection (marked failed, not
  // restartable); after an I/O failure nothing more is written but the report.
  std::string saved, saveError;
  // (not after an allocation failure: writing the state would allocate more)
  if (checkpoint_.onFailure && v.code == kRunFailedStatus && !outOfMemory(v.message)) {
    const std::string path = failedCheckpointPath(checkpoint_.pathAt(simulation_->steps() + 1));
    const auto w = phase(channel_, kRunFailedStatus, [&] {
      simulation_->writeCheckpoint(path, "failed: " + when + ": " + v.message);
    });
    if (w.failed())
      saveError = w.message;
    else
      saved = path;
  }
  if (root_) {
    log_.err("coloc: error: {}: {}\n", when, v.message);
    if (!saved.empty())
      log_.err(
          "coloc: the state at the failure is in {} (status 'failed'; not "
          "restartable){}{}\n",
          saved, lastCheckpoint_.empty() ? "" : "; last good checkpoint: ", lastCheckpoint_);
    else if (!lastCheckpoint_.empty())
      log_.err("coloc: last good checkpoint: {}\n", lastCheckpoint_);
    if (!saveError.empty()) log_.err("coloc: could not write the failed state: {}\n", saveError);
  }
  writeReport("failed", v.code, when + ": " + v.message, saved.empty() ? lastCheckpoint_ : saved,
              0);
  return v.code;
}

/// Stopped (a batch system's wall-time limit): every rank after the same step, with a
/// checkpoint and a report marked interrupted. Returns 128 + the signal.
int Run::stopBySignal(int sig) {
  std::string path = checkpoint_.pathAt(simulation_->steps());
  std::string saveError;
  if (!checkpoint_.due(simulation_->steps())) {
    const auto w = phase(channel_, kIoErrorStatus, [&] { simulation_->writeCheckpoint(path); });
    if (w.failed()) {
      saveError = w.message;
      path = lastCheckpoint_;
    }
  }
  const std::string report = writeReport("interrupted", kInterruptedBase + sig,
                                         std::string("stopped by ") + signalName(sig), path, sig);
  if (root_) {
    log_.err(
        "coloc: stopped by {} after step {} (t = {:.9g} s); checkpoint: {}; "
        "report: {}; exit status {}\n",
        signalName(sig), simulation_->steps(), simulation_->time(),
        path.empty() ? "none" : path.c_str(), report.empty() ? "none" : report.c_str(),
        kInterruptedBase + sig);
    if (!saveError.empty())
      log_.err("coloc: error: could not write the final checkpoint: {}\n", saveError);
  }
  return kInterruptedBase + sig;
}

/// 4. The final state, unless the last step wrote it already; then the report and the summary;
/// the snapshot is left to main() (rank 0), after MPI_Finalize.
int Run::finish(std::optional<SnapshotJob>& snapshot) {
  if (checkpoint_.intervalSteps > 0 && !checkpoint_.due(simulation_->steps())) {
    const std::string path = checkpoint_.pathAt(simulation_->steps());
    const auto v = phase(channel_, kIoErrorStatus, [&] { simulation_->writeCheckpoint(path); });
    if (v.failed()) {
      say(v, "writing the final checkpoint: ");
      writeReport("failed", v.code, "writing the final checkpoint: " + v.message, lastCheckpoint_,
                  0);
      return v.code;
    }
    lastCheckpoint_ = path;
  }
  if (root_) series_->sync();
  if (root_ && simulation_->biotMax() > coupling::Simulation::kBiotLimit)
    log_.err(
        "coloc: warning: particle Biot number up to {:.3g} (> {:g}): the lumped-capacitance "
        "particle temperature (particles.heat) is no longer accurate; report.json "
        "coupling.heat_transfer.biot_max\n",
        simulation_->biotMax(), coupling::Simulation::kBiotLimit);
  if (root_ && unconvergedWarned_ > 0)
    log_.err(
        "coloc: warning: {} pressure solve(s) of this run did not converge "
        "(report.json fluid.unconverged_solves)\n",
        unconvergedWarned_);
  const std::string path = writeReport("ok", 0, "", lastCheckpoint_, 0);
  if (path.empty()) return kIoErrorStatus;
  if (root_) printSummary(path);
  if (world_.isRoot()) snapshot = snapshotDue(cfg_, outDir_, opts_.quiet);
  return 0;
}

/// Rank 0: the run in one line, the phases of the loop over the ranks (LAMMPS's timing
/// breakdown) and the figure of merit, all from the report just written.
void Run::printSummary(const std::string& reportPath) {
  const Json& j = written_;
  {
    // The steps of this run: after a restart, those from the checkpoint's step on.
    const auto start = simulation_->runStart();
    const long long last = j["run"]["steps"].get<long long>();
    const std::string resumed =
        start[0] > 0 ? fmt::format(", steps {}-{} after the restart", start[0] + 1, last) : "";
    log_.out(
        "coloc: {} steps ({} DEM sub-steps){}, t = {:.6g} s, {:.3f} s wall, "
        "{:.3g} cell-steps/s, {:.3g} particle-steps/s, inter-physics {:.3f}% of the step\n",
        last - start[0], j["run"]["dem_substeps"].get<long long>() - start[1], resumed,
        j["run"]["sim_time"].get<double>(), j["run"]["wall_s"].get<double>(),
        j["throughput"]["cell_steps_per_s"].get<double>(),
        j["throughput"]["particle_steps_per_s"].get<double>(),
        100.0 * j["fractions"]["inter_physics"].get<double>());
  }
  // With --quiet the phase table goes to the log only.
  for (const std::string& line : phaseTable(j))
    if (opts_.quiet)
      log_.file("coloc: {}\n", line);
    else
      log_.out("coloc: {}\n", line);
  if (j.contains("figure_of_merit")) log_.out("{}\n", figureOfMeritLine(j["figure_of_merit"]));
  log_.out("coloc: report written to {}\n", reportPath);
}

}  // namespace

int runCase(const Comm& world, const RunOptions& opts, std::optional<SnapshotJob>& snapshot) {
  Run run(world, opts);
  if (const int code = run.prepareFolders()) return code;
  if (const int code = run.setUp()) return code;
  if (const int code = run.stepLoop()) return code;
  return run.finish(snapshot);
}

}  // namespace coloc
