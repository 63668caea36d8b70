#include "run.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
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
#include "progress.hpp"
#include "restart_account.hpp"
#include "run_folder.hpp"
#include "run_log.hpp"
#include "summary.hpp"

namespace coloc {
namespace {

/// A per-step time series (series.csv): coupling totals, the particles of
/// output.series_particles / output.series_particle_ids, and the bed diagnostics
/// (diagnostics.hpp) on the steps of output.diagnostics_interval and the last step (empty fields
/// in the other rows).
/// Rank 0 writes the header to series.csv.tmp and renames it (an old series.csv is replaced whole),
/// then appends each row with one write(); a row that cannot be written whole is cut off again
/// (ftruncate), so the file holds whole rows only, and the error waits in error() for the step's
/// agreement (no extra collective).
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
    path_ = path;
    std::string header = "step,time,solid_volume,fluid_accel_l1";
    for (long long id : ids_)
      for (const char* q : {"x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz"})
        header += ",p" + std::to_string(id) + "_" + q;
    for (const auto& c : bedDiagnosticsColumns()) header += "," + c;
    header += "\n";
    line_.reserve(32 * (4 + 9 * ids_.size() + bedDiagnosticsColumns().size()));
    const std::string tmp = path + ".tmp";
    fd_ = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0) throw IoError("cannot create '" + tmp + "': " + std::strerror(errno));
    if (!append(header) || ::rename(tmp.c_str(), path.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      ::close(fd_);
      fd_ = -1;
      ::unlink(tmp.c_str());
      throw IoError("cannot write '" + path + "': " + why);
    }
  }
  ~Series() {
    if (fd_ >= 0) ::close(fd_);
  }
  Series(const Series&) = delete;
  Series& operator=(const Series&) = delete;

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
    if (!comm_.isRoot() || fd_ < 0 || !error_.empty()) return diag;
    try {
      fault::point("series", sim.steps());
    } catch (const std::exception& e) {
      error_ = e.what();
      return diag;
    }
    char buf[64];
    line_ = std::to_string(sim.steps());
    for (double v : {sim.time(), sim.depositedSolidVolume(), sim.fluidAccelerationL1()}) {
      std::snprintf(buf, sizeof buf, ",%.17g", v);
      line_ += buf;
    }
    for (double v : row) {
      std::snprintf(buf, sizeof buf, ",%.17g", v);
      line_ += buf;
    }
    if (diag) {
      for (double v : bedDiagnosticsRow(*diag)) {
        std::snprintf(buf, sizeof buf, ",%.17g", v);
        line_ += buf;
      }
    } else {
      line_ += std::string(bedDiagnosticsColumns().size(), ',');
    }
    line_ += "\n";
    if (!append(line_))
      error_ = "cannot append to '" + path_ + "': " + std::strerror(errno) +
               " (the rows before this step are kept)";
    return diag;
  }
  /// Rank 0: the write error of the last record(), if any (then the series stops growing).
  const std::string& error() const { return error_; }
  /// Rank 0: to stable storage (with each checkpoint, at the end).
  void sync() {
    if (fd_ >= 0) ::fsync(fd_);
  }

 private:
  /// One write() of the whole text; on a short or failed write the file is cut back.
  bool append(const std::string& text) {
    const off_t before = ::lseek(fd_, 0, SEEK_END);
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const int e = n == 0 ? ENOSPC : errno;
        if (before >= 0 && ::ftruncate(fd_, before) != 0) {
        }
        errno = e;
        return false;
      }
      done += static_cast<std::size_t>(n);
    }
    return true;
  }
  const Comm& comm_;
  const Config& cfg_;
  std::vector<long long> ids_;
  std::map<long long, std::size_t> column_;
  long long diagEvery_ = 0;
  int fd_ = -1;
  std::string path_, line_, error_;
};

/// output.snapshot: rank 0 runs bench/scripts/snapshot.py on the run's output (a picture of the
/// last fields and particles, OUT/snapshot.png). Only a warning when it cannot.
void drawSnapshot(const Config& cfg, const std::string& outDir, bool quiet, RunLog& log) {
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
                          quote((fs::path(outDir) / "report.json").string()) + " 2>&1";
  std::fflush(stdout);
  // What the script says goes to the terminal (unless --quiet) and the log.
  int rc = -1;
  if (std::FILE* pipe = ::popen(cmd.c_str(), "r")) {
    char line[1024];
    while (std::fgets(line, sizeof line, pipe))
      if (quiet)
        log.file("{}", line);
      else
        log.out("{}", line);
    rc = ::pclose(pipe);
  }
  if (rc != 0)
    log.err(
        "coloc: warning: no snapshot.png ({} exited with status {}); the run's output "
        "is complete (set output.snapshot=false to skip the picture)\n",
        script.string(), rc);
}

/// The stop signal received so far (0: none); set by the handler installStopSignals() puts in.
volatile std::sig_atomic_t stopSignal = 0;

extern "C" void onStopSignal(int sig) {
  if (stopSignal != 0) {  // the second: at once (async-signal-safe calls only)
    static const char msg[] = "coloc: second stop signal: exiting now, without a checkpoint\n";
    const ssize_t n = ::write(2, msg, sizeof msg - 1);
    (void)n;
    std::_Exit(kInterruptedBase + sig);
  }
  stopSignal = sig;
}

const char* signalName(int sig) {
  switch (sig) {
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    default:
      return "a signal";
  }
}

/// The start of the message of an allocation failure (report.json: out_of_memory).
constexpr const char* kOutOfMemory = "out of memory";

bool outOfMemory(const std::string& message) {
  return message.find(kOutOfMemory) != std::string::npos;
}

/// What libraryAborted() needs of the run in progress (set by runCase while it runs; the
/// abort comes from inside a library, with no way back to runCase's frame).
struct LastWords {
  const Comm* world = nullptr;
  std::string casePath, outDir;
  const Json* config = nullptr;
  const Json* provenance = nullptr;
};
LastWords lastWords;

/// Runs `f` on every rank and agrees on the outcome at its end (coloc/core/failure.hpp): the
/// exit status by the error's type (IoError: kIoErrorStatus, other coloc::Error: `errorCode`,
/// anything else: kRunFailedStatus), the message of the lowest failing rank, and `where`, a
/// number the caller gives the part of the phase that was running (set through the pointer),
/// and `request`, a flag any rank may raise for the verdict (read after `f`; progress.hpp).
template <class F>
FailureChannel::Verdict phase(const FailureChannel& channel, int errorCode, F&& f,
                              int* where = nullptr, const int* request = nullptr) {
  std::string err;
  int code = 0;
  try {
    f();
  } catch (const IoError& e) {
    err = e.what();
    code = kIoErrorStatus;
  } catch (const Error& e) {
    err = e.what();
    code = errorCode;
  } catch (const std::bad_alloc& e) {
    err = std::string(kOutOfMemory) + " (" + e.what() +
          "): an allocation failed; the memory estimate (coloc check) did not foresee it";
    code = kRunFailedStatus;
  } catch (const std::exception& e) {
    err = std::string("unexpected exception: ") + e.what();
    code = kRunFailedStatus;
  }
  return channel.agree(err, code, static_cast<int>(stopSignal), where ? *where : 0,
                       request ? *request : 0);
}

/// Runs `f` on rank 0 only and throws its coloc::Error (an IoError as one) on every rank, so
/// that a check only rank 0 makes (the output folder, its lock) is reported like an input error
/// every rank found, without a "rank 0:" prefix. Collective.
template <class F>
void onRoot(const Comm& world, F&& f) {
  std::string err;
  if (world.isRoot()) {
    try {
      f();
    } catch (const IoError& e) {
      err = std::string("I") + e.what();
    } catch (const std::exception& e) {  // a coloc::Error, or std::filesystem's
      err = std::string("E") + e.what();
    }
  }
  err = world.broadcast(err);
  if (err.empty()) return;
  if (err[0] == 'I') throw IoError(err.substr(1));
  throw Error(err.substr(1));
}

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
  msg = "rank " + std::to_string(rank) + ": " + msg;
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
      {
        std::ofstream out(tmp, std::ios::trunc);
        out << report.json().dump(2) << "\n";
      }
      std::filesystem::rename(tmp, dir / "report.json");
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

void installStopSignals() {
  struct sigaction a {};
  a.sa_handler = onStopSignal;
  sigemptyset(&a.sa_mask);
  a.sa_flags = SA_RESTART;
  sigaction(SIGTERM, &a, nullptr);
  sigaction(SIGINT, &a, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);  // a write past RLIMIT_FSIZE fails with EFBIG: an I/O error
}

int runCase(const Comm& world, const RunOptions& opts) {
  const double t0 = MPI_Wtime();
  // Phase agreements go through a communicator of their own (coloc/core/failure.hpp).
  const FailureChannel channel(world);
  const Config cfg = Config::load(world, opts.casePath, opts.overrides, coupling::caseSchema());
  // Whole-case checks and the memory estimate, before anything large is allocated.
  const std::vector<std::string> notes = coupling::checkCase(cfg);
  coupling::checkMemory(world, cfg);
  // Rank 0's messages, also into OUT/log.txt once the folder is ready (the lines before kept).
  RunLog log(world.isRoot());
  for (const auto& n : notes) log.out("coloc: note: {}\n", n);
  setFailureWait(cfg.number("run.failure_wait_s"));
  // Where the run comes from (collective): report.json's "provenance".
  Json prov = provenance(world, opts.commandLine);
  prov["hypre_version"] = fv::hypreVersion();
  prov["hdf5_version"] = hdf5Version();
  const std::string outDir = opts.outDir.empty()
                                 ? (std::filesystem::path("out") / cfg.string("name")).string()
                                 : opts.outDir;
  const CheckpointOptions checkpoint = checkpointOptionsFromConfig(cfg, outDir);
  const OutputOptions outputOptions = outputOptionsFromConfig(cfg, outDir);
  const bool root = world.isRoot();
  // For libraryAborted(), while this run is in progress.
  lastWords = {&world, opts.casePath, outDir, &cfg.json(), &prov};
  struct ClearLastWords {
    ~ClearLastWords() { lastWords = {}; }
  } clearLastWords;
  const auto say = [&](const FailureChannel::Verdict& v, const std::string& before) {
    log.err("coloc: error: {}{}\n", before, v.message);
  };

  // 1. The output folders (rank 0): made; locked against a second run for as long as this one
  // lasts; the checkpoint kept inside them and off the --restart file; an earlier run's files
  // refused (or removed with --overwrite); what a previous run left there that would mislead
  // removed. A --restart that is no regular file (a FIFO would block the
  // read) is refused before anything is made.
  const RunFolders folders{outDir, outputOptions.dir, cfg.string("output.checkpoint_file")};
  FolderLocks locks;
  std::vector<std::string> earlierFiles;  // rank 0: an earlier run's files, for --overwrite
  auto v = phase(channel, kInputErrorStatus, [&] {
    onRoot(world, [&] {
      if (opts.restart.empty()) return;
      if (const std::string why = notRegularFile(opts.restart); !why.empty())
        throw ConfigError("--restart",
                          "'" + opts.restart + (why == "no such file" ? "': " : "' ") + why);
    });
  });
  if (!v.failed())
    v = phase(channel, kIoErrorStatus, [&] {
      onRoot(world, [&] {
        makeDirectories(outDir);
        makeDirectories(folders.dataDir);
      });
    });
  if (!v.failed())
    v = phase(channel, kInputErrorStatus, [&] {
      onRoot(world, [&] {
        locks.lock(outDir, "--out", opts.casePath);
        std::error_code ec;
        if (!std::filesystem::equivalent(outDir, folders.dataDir, ec))
          locks.lock(folders.dataDir, "output.dir", opts.casePath);
        checkRunFiles(folders, opts.restart);
        // Two runs never mix in one folder: an earlier run's files refuse the run, unless it
        // continues that run (--restart of a checkpoint there) or replaces it (--overwrite).
        if (!restartInFolders(folders, opts.restart)) {
          earlierFiles = previousRunFiles(folders);
          if (!opts.overwrite) refuseMixedRuns(folders, earlierFiles);
        }
      });
    });
  if (!v.failed())
    v = phase(channel, kIoErrorStatus, [&] {
      if (!root) return;
      removeRunFiles(earlierFiles);
      removeStaleFiles(folders);
      fault::point("outdir", 0);
      log.open((std::filesystem::path(outDir) / "log.txt").string(),
               restartInFolders(folders, opts.restart));
    });
  if (v.failed()) {
    say(v, "");
    return v.code;
  }

  // What report.json says of the run, however it ends (collective; a failure to write it is
  // printed, the exit status stays that of the run).
  std::unique_ptr<coupling::Simulation> simulation;
  long long rebalances = 0;
  double setupWall = 0, tLoop = 0;
  Json written;                                   // the last report written
  Json restartReport;                             // a restart: what came from where
  long long unconvergedWarned = 0;                // pressure solves above tol, warned of
  std::optional<BedDiagnostics> lastDiagnostics;  // of the last series row that had them
  const auto writeReport = [&](const char* status, int code, const std::string& error,
                               const std::string& state, int sig) -> std::string {
    std::string path;
    const auto r = phase(channel, kIoErrorStatus, [&] {
      Report report(opts.casePath, cfg.json());
      if (simulation) report.merge(simulation->report(tLoop > 0 ? MPI_Wtime() - tLoop : 0.0));
      report.set("status", status);
      report.set("exit_code", code);
      report.set("provenance", prov);
      if (simulation) report.set("figure_of_merit", figureOfMerit(report.json()));
      if (!error.empty()) report.set("error", error);
      if (outOfMemory(error)) report.set("out_of_memory", true);
      if (!restartReport.is_null()) report.set("restart", restartReport);
      if (!state.empty()) report.set("checkpoint", state);
      if (sig != 0) report.set("signal", signalName(sig));
      report.set("run.setup_s", world.max(setupWall));
      report.set("partition.rebalances", rebalances);
      report.set("run.notes", notes);
      // The bed as it ends: computed now at a good end, the last computed otherwise.
      if (lastDiagnostics)
        report.set("bed", bedDiagnosticsJson(*lastDiagnostics));
      else if (simulation && code == 0)
        report.set("bed", bedDiagnosticsJson(bedDiagnostics(*simulation, cfg)));
      report.set("run.total_wall_s", world.max(MPI_Wtime() - t0));
      report.addMemory(world);
      fault::point("report", simulation ? simulation->steps() : 0);
      path = report.write(world, outDir);
      written = report.json();
    });
    if (r.failed() && root) log.err("coloc: error: could not write the report: {}\n", r.message);
    return r.failed() ? std::string() : path;
  };

  // 2. Set-up: the physics, the series, the output of step 0.
  // A progress row: rank 0's clock asks for one at the end of the set-up or a step (`request`,
  // carried by its agreement); every rank computes it on the next step, and on the last.
  std::optional<Progress> progress;
  int request = 0;
  std::optional<Series> series;
  std::optional<OutputWriter> output;
  v = phase(
      channel, kInputErrorStatus,
      [&] {
        if (opts.restart.empty())
          simulation = std::make_unique<coupling::Simulation>(world, cfg);
        else
          simulation = std::make_unique<coupling::Simulation>(
              cfg, coupling::Simulation::restartLayouts(world, cfg, opts.restart), opts.restart);
        setupWall = MPI_Wtime() - t0;
        const long long particleCount =
            simulation->particles() ? simulation->particles()->globalCount() : 0;  // collective
        if (root && !opts.quiet) {
          const auto& dec = simulation->decomposition();
          log.out(
              "coloc: case '{}', mode {}, {} rank(s) as {}, {} cells, {} particles, "
              "set-up {:.2f} s\n",
              cfg.string("name"), runModeName(simulation->mode()), dec.size(), dec.shape(),
              static_cast<long long>(dec.grid().cellCount()), particleCount, setupWall);
          if (!opts.restart.empty())
            log.out("coloc: restarted from {} at step {}, t = {:.9g} s\n", opts.restart,
                    simulation->steps(), simulation->time());
        }
        if (!opts.restart.empty()) {
          restartReport = accountRestart(world, opts.restart, cfg, log);
          refuseEmptyRestart(cfg, opts.restart, simulation->steps(), simulation->time());
        }
        progress.emplace(world, cfg, opts.quiet ? 0.0 : cfg.number("run.progress_interval_s"), log);
        series.emplace(world, (std::filesystem::path(outDir) / "series.csv").string(), *simulation,
                       cfg);
        output.emplace(simulation->decomposition(), outputOptions);
        simulation->writeOutput(*output);
        progress->start(*simulation);  // the header and the first row
        request = progress->request();
      },
      nullptr, &request);
  if (v.failed()) {
    say(v, "");
    writeReport("failed", v.code, v.message, "", 0);
    return v.code;
  }

  // 3. The time loop: one agreement per step, after the step and its output, series,
  // checkpoint and re-balance; it carries the stop signals too.
  enum Part { kStep = 0, kOutput, kSeries, kCheckpoint, kRebalance };
  static const char* const kPartName[] = {"the step", "writing the output", "writing series.csv",
                                          "writing the checkpoint", "re-balancing"};
  // The keys the loop needs, parsed once (no string look-ups inside the loop).
  const long long rebalanceEvery = coupling::rebalanceInterval(cfg);
  const bool rebalanceThroughFile = cfg.string("partition.rebalance_move") == "file";
  const std::string rebalanceScratch =
      (std::filesystem::path(outDir) / "rebalance.tmp.h5").string();
  const long long pressureMaxIter = cfg.integer("fluid.pressure.max_iter");
  const double pressureTol = cfg.number("fluid.pressure.tol");
  simulation->beginRun();
  tLoop = MPI_Wtime();
  std::string lastCheckpoint;
  bool rowDue = v.request != 0;
  while (!simulation->finished()) {
    int where = kStep;
    v = phase(
        channel, kRunFailedStatus,
        [&] {
          where = kStep;
          simulation->step();
          where = kOutput;
          simulation->writeOutput(*output);
          where = kSeries;
          if (auto d = series->record(*simulation)) lastDiagnostics = std::move(d);
          if (checkpoint.due(simulation->steps())) {
            where = kCheckpoint;
            if (root) series->sync();
            simulation->writeCheckpoint(checkpoint.pathAt(simulation->steps()));
            lastCheckpoint = checkpoint.pathAt(simulation->steps());
          }
          if (coupling::rebalanceDue(rebalanceEvery, simulation->steps())) {
            where = kRebalance;
            const auto plan = coupling::planRebalance(*simulation, cfg);
            if (plan.layouts) {
              simulation =
                  rebalanceThroughFile
                      ? coupling::applyRebalanceThroughFile(std::move(simulation), cfg,
                                                            *plan.layouts, rebalanceScratch)
                      : coupling::applyRebalance(std::move(simulation), cfg, *plan.layouts);
              output->rebind(simulation->decomposition());
              ++rebalances;
              if (root && !opts.quiet) {
                log.out(
                    "coloc: step {}: re-balanced onto {}, modelled imbalance {:.3f} -> {:.3f}\n",
                    simulation->steps(), simulation->decomposition().shape(), plan.currentImbalance,
                    plan.newImbalance);
              }
            }
          }
          progress->row(*simulation, rowDue || simulation->finished());
          request = progress->request();
          if (root && simulation->fluid()) {
            // The same count on every rank (hypre's norms are global); printed once.
            const fv::FluidCounters c = simulation->fluid()->counters();
            if (c.unconverged > 0 && unconvergedWarned == 0)
              log.err(
                  "coloc: warning: step {}: the pressure solve did not converge "
                  "(residual {:.3g} of the flux scale after {} iterations, "
                  "fluid.pressure.max_iter = {}, tol = {:g}); counted in report.json "
                  "fluid.unconverged_solves (fluid.pressure.on_no_convergence = error "
                  "stops the run)\n",
                  simulation->steps(), c.resLast, c.itLast, pressureMaxIter, pressureTol);
            unconvergedWarned = c.unconverged;
          }
          // Rank 0's series error, after every collective of the step: agreed cleanly.
          if (root && !series->error().empty()) {
            where = kSeries;
            throw IoError(series->error());
          }
        },
        &where, &request);
    rowDue = v.request != 0;
    if (v.failed()) {
      if (!simulation) {  // failed while moving onto new blocks: no state left in memory
        say(v, "re-balancing failed: ");
        writeReport("failed", v.code, "re-balancing failed: " + v.message, "", 0);
        return v.code;
      }
      char when[200];
      if (v.where == kStep)
        std::snprintf(when, sizeof when, "the run failed in step %lld (from t = %.9g s)",
                      simulation->steps() + 1, simulation->time());
      else
        std::snprintf(when, sizeof when, "the run failed after step %lld (t = %.9g s), %s",
                      simulation->steps(), simulation->time(),
                      kPartName[std::clamp(v.where, 0, 4)]);
      // The state at a failure of the physics is kept for inspection (marked failed, not
      // restartable); after an I/O failure nothing more is written but the report.
      std::string saved, saveError;
      // (not after an allocation failure: writing the state would allocate more)
      if (checkpoint.onFailure && v.code == kRunFailedStatus && !outOfMemory(v.message)) {
        const std::string path = failedCheckpointPath(checkpoint.pathAt(simulation->steps() + 1));
        const auto w = phase(channel, kRunFailedStatus, [&] {
          simulation->writeCheckpoint(path, "failed: " + std::string(when) + ": " + v.message);
        });
        if (w.failed())
          saveError = w.message;
        else
          saved = path;
      }
      if (root) {
        log.err("coloc: error: {}: {}\n", when, v.message);
        if (!saved.empty())
          log.err(
              "coloc: the state at the failure is in {} (status 'failed'; not "
              "restartable){}{}\n",
              saved, lastCheckpoint.empty() ? "" : "; last good checkpoint: ", lastCheckpoint);
        else if (!lastCheckpoint.empty())
          log.err("coloc: last good checkpoint: {}\n", lastCheckpoint);
        if (!saveError.empty()) log.err("coloc: could not write the failed state: {}\n", saveError);
      }
      writeReport("failed", v.code, std::string(when) + ": " + v.message,
                  saved.empty() ? lastCheckpoint : saved, 0);
      return v.code;
    }
    if (v.signal != 0 && !simulation->finished()) {
      // Stopped (a batch system's wall-time limit): every rank after the same step.
      const int sig = v.signal;
      std::string path = checkpoint.pathAt(simulation->steps());
      std::string saveError;
      if (!checkpoint.due(simulation->steps())) {
        const auto w = phase(channel, kIoErrorStatus, [&] { simulation->writeCheckpoint(path); });
        if (w.failed()) {
          saveError = w.message;
          path = lastCheckpoint;
        }
      }
      const std::string report =
          writeReport("interrupted", kInterruptedBase + sig,
                      std::string("stopped by ") + signalName(sig), path, sig);
      if (root) {
        log.err(
            "coloc: stopped by {} after step {} (t = {:.9g} s); checkpoint: {}; "
            "report: {}; exit status {}\n",
            signalName(sig), simulation->steps(), simulation->time(),
            path.empty() ? "none" : path.c_str(), report.empty() ? "none" : report.c_str(),
            kInterruptedBase + sig);
        if (!saveError.empty())
          log.err("coloc: error: could not write the final checkpoint: {}\n", saveError);
      }
      return kInterruptedBase + sig;
    }
  }

  // 4. The final state, unless the last step wrote it already; then the report.
  if (checkpoint.intervalSteps > 0 && !checkpoint.due(simulation->steps())) {
    const std::string path = checkpoint.pathAt(simulation->steps());
    v = phase(channel, kIoErrorStatus, [&] { simulation->writeCheckpoint(path); });
    if (v.failed()) {
      say(v, "writing the final checkpoint: ");
      writeReport("failed", v.code, "writing the final checkpoint: " + v.message, lastCheckpoint,
                  0);
      return v.code;
    }
    lastCheckpoint = path;
  }
  if (root) series->sync();
  if (root && unconvergedWarned > 0)
    log.err(
        "coloc: warning: {} pressure solve(s) of this run did not converge "
        "(report.json fluid.unconverged_solves)\n",
        unconvergedWarned);
  const std::string path = writeReport("ok", 0, "", lastCheckpoint, 0);
  if (path.empty()) return kIoErrorStatus;
  if (root) {
    const Json& j = written;
    {
      // The steps of this run: after a restart, those from the checkpoint's step on.
      const auto start = simulation->runStart();
      const long long last = j["run"]["steps"].get<long long>();
      char resumed[96] = "";
      if (start[0] > 0)
        std::snprintf(resumed, sizeof resumed, ", steps %lld-%lld after the restart", start[0] + 1,
                      last);
      log.out(
          "coloc: {} steps ({} DEM sub-steps){}, t = {:.6g} s, {:.3f} s wall, "
          "{:.3g} cell-steps/s, {:.3g} particle-steps/s, inter-physics {:.3f}% of the step\n",
          last - start[0], j["run"]["dem_substeps"].get<long long>() - start[1], resumed,
          j["run"]["sim_time"].get<double>(), j["run"]["wall_s"].get<double>(),
          j["throughput"]["cell_steps_per_s"].get<double>(),
          j["throughput"]["particle_steps_per_s"].get<double>(),
          100.0 * j["fractions"]["inter_physics"].get<double>());
    }
    // The phases of the loop over the ranks (LAMMPS's timing breakdown) and the figure of merit,
    // both from the report just written; with --quiet in the log only.
    for (const std::string& line : phaseTable(j))
      if (opts.quiet)
        log.file("coloc: {}\n", line);
      else
        log.out("coloc: {}\n", line);
    if (j.contains("figure_of_merit")) log.out("{}\n", figureOfMeritLine(j["figure_of_merit"]));
    log.out("coloc: report written to {}\n", path);
  }
  if (world.isRoot()) drawSnapshot(cfg, outDir, opts.quiet, log);
  return 0;
}

}  // namespace coloc
