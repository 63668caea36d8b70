// coloc — the command-line driver.
//
//   coloc run CASE.json [--set key.path=value ...] [--out DIR] [--restart CHECKPOINT.h5]
//             [--overwrite]
//   coloc keys [PREFIX]   each case-file key (or those under PREFIX): type, default, range, meaning
//   coloc check CASE.json [--ranks N] [--set ...]   validate, show layouts/memory/time steps
//   coloc plan CASE.json --ranks 28,56,1024 [--strategy S ...] [--set ...] [--out DIR]
//                         layouts, work and traffic per rank for rank counts not run (one process)
//   coloc snapshot OUT_DIR [--png FILE] [--full] [--step N]
//                         snapshot.png of a finished run's last output (no MPI, no mpirun)
//   coloc --help
//
// Errors in the input are found identically on every rank: rank 0 prints one message naming the
// key, and every rank exits with status 2. Nothing waits in a collective. A run that fails inside
// the time loop (a blow-up) exits with status 3 on every rank, an output that cannot be written
// with 4, a run stopped by SIGTERM/SIGINT with 128 + the signal (bench/driver/run.hpp,
// docs/robustness.md).
#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string_view>

#include "check.hpp"
#include "coloc/core/comm.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"
#include "coloc/core/provenance.hpp"
#include "coloc/coupling/library_version.hpp"
#include "coloc/fv/library_version.hpp"
#include "coloc/io/library_version.hpp"
#include "data_dir.hpp"
#include "plan.hpp"
#include "run.hpp"
#include "snapshot.hpp"
#include "stop_signals.hpp"

// hypre (2.26) answers a failed allocation with MPI_Abort(MPI_COMM_WORLD, -1) and no way to
// intercept it through its API: the driver's own MPI_Abort (the MPI profiling interface; the
// real one is PMPI_Abort) turns that into a coloc error with a report (run.hpp,
// libraryAborted). coloc's own aborts (status 2, 3, 4) pass through.
extern "C" int MPI_Abort(MPI_Comm comm, int errorcode) {
  if (errorcode == -1) coloc::libraryAborted();
  return PMPI_Abort(comm, errorcode);
}

namespace {

/// `coloc --version`: the version and what the binary was built from and with (as `lmp -h`
/// shows LAMMPS's build): commit, compiler, flags, the libraries, where its scripts are.
std::string versionText() {
  std::string text = coloc::buildDescription();
  text += "  hypre:       " + coloc::fv::hypreVersion() + "\n";
  text += "  HDF5:        " + coloc::hdf5Version() + " (parallel)\n";
  text += "  SLEEF:       " + coloc::coupling::sleefVersion() + "\n";
  text += "  headers:     Eigen " + std::to_string(EIGEN_WORLD_VERSION) + "." +
          std::to_string(EIGEN_MAJOR_VERSION) + "." + std::to_string(EIGEN_MINOR_VERSION) +
          ", {fmt} " + std::to_string(FMT_VERSION / 10000) + "." +
          std::to_string(FMT_VERSION / 100 % 100) + "." + std::to_string(FMT_VERSION % 100) +
          ", nlohmann_json " + std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
          std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
          std::to_string(NLOHMANN_JSON_VERSION_PATCH) + ", CLI11 " + CLI11_VERSION + "\n";
  text += "  data:        " + coloc::dataDir().string() + " (scripts, cases)";
  return text;
}

/// Every subcommand but `coloc snapshot`, between MPI_Init and MPI_Finalize (main()). Returns
/// the exit status; a run that asks for its picture sets `snapshot` (rank 0).
int mpiMain(int argc, char** argv, std::optional<coloc::SnapshotJob>& snapshot) {
  const coloc::Comm world = coloc::Comm::world();

  CLI::App app{
      "coloc: co-located partitions CFD-DEM mini-app (fluid cells and the particles in\n"
      "the same region live on the same MPI rank). Run with mpirun -n N coloc run CASE."};
  app.require_subcommand(1);
  app.set_version_flag("--version", versionText(),
                       "the version, git commit, compiler, flags and libraries of this build");
  coloc::RunOptions opts;
  opts.commandLine = coloc::commandLineText(argc, argv);
  auto* run = app.add_subcommand("run", "run a case file and write DIR/report.json");
  run->add_option("case", opts.casePath, "case file (JSON, // comments allowed)")->required();
  run->add_option("--set", opts.overrides,
                  "override a case key, e.g. --set run.steps=20 (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  run->add_option("--out", opts.outDir, "output directory (default: out/<case name>)");
  run->add_flag("--quiet", opts.quiet, "no progress lines");
  run->add_flag("--overwrite", opts.overwrite,
                "the output folders may hold an earlier run's files (report.json, fields.xmf, "
                "checkpoints, ...): remove them before the run (without it such a folder is "
                "refused, unless --restart continues from a checkpoint in it)");
  run->add_option("--restart", opts.restart,
                  "continue from this checkpoint (output.checkpoint_*) instead of the case's "
                  "initial condition, on any rank count; run.steps/run.end_time count from the "
                  "start of the original run");
  std::string keysPrefix;
  auto* keys =
      app.add_subcommand("keys", "list every case-file key with type, default, range and meaning");
  keys->add_option("prefix", keysPrefix,
                   "only the keys under this path, e.g. particles.sources or fluid.dt");
  coloc::CheckOptions check;
  check.commandLine = opts.commandLine;
  auto* checkCmd = app.add_subcommand(
      "check",
      "validate a case and print the layout each partition strategy would choose for N "
      "ranks, cells and particles a rank, the memory estimate and the time-step limits; "
      "runs nothing, in one process (exit 0: valid, 2: a run would be refused)");
  checkCmd->add_option("case", check.casePath, "case file (JSON, // comments allowed)")->required();
  checkCmd->add_option("--ranks", check.ranks, "rank count to lay the case out for (default 1)");
  checkCmd->add_option("--set", check.overrides, "override a case key (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  checkCmd->add_flag("--cuts", check.verbose, "print every strategy's cuts");
  checkCmd->add_option("--draw", check.drawPath,
                       "also draw every strategy's layout on the vertical mid-plane (an SVG file: "
                       "blocks numbered by rank over the particles a cell)");
  checkCmd
      ->add_option("--plane", check.plane,
                   "with --draw: the plane drawn by its two axes, cut at the middle cell of the "
                   "third (default: the vertical mid-plane along the longer horizontal axis)")
      ->check(CLI::IsMember({"xz", "yz", "xy"}))
      ->needs("--draw");
  coloc::PlanOptions planOpts;
  auto* plan = app.add_subcommand(
      "plan",
      "the blocks each strategy chooses for rank counts that are not run, and each "
      "rank's cells, particles, ghosts and exchange bytes/messages per step (one "
      "process): DIR/plan.json, DIR/plan.csv");
  plan->add_option("case", planOpts.casePath, "case file")->required();
  plan->add_option("--ranks", planOpts.ranks, "rank counts, comma-separated, e.g. 28,56,1024")
      ->required();
  plan->add_option("--strategy", planOpts.strategies,
                   "uniform, balanced, independent, tiled (repeatable; default: the first "
                   "three, tiled only when named: docs/plan.md)");
  plan->add_option("--set", planOpts.overrides, "override a case key (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  plan->add_option("--out", planOpts.outDir, "output directory (default: out/<case name>/plan)");
  // Listed here for --help; main() runs it before MPI_Init.
  coloc::SnapshotJob snapshotJob;
  coloc::addSnapshotCommand(app, snapshotJob);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::ostringstream out, err;
    const int code = app.exit(e, out, err);
    if (world.isRoot()) {
      std::cout << out.str();
      std::cerr << err.str();
      if (code != 0) std::cerr << "Run 'coloc --help' for usage.\n";
    }
    return code == 0 ? 0 : 2;
  }

  try {
    if (app.got_subcommand("keys")) {
      const std::string text = coloc::describeKeys(keysPrefix);  // same verdict on every rank
      if (world.isRoot())
        std::cout << (keysPrefix.empty() ? "" : "Case-file keys under '" + keysPrefix + "':\n")
                  << text;
      return 0;
    }
    if (app.got_subcommand("check")) {
      // One process does the work (no mpirun needed); under mpirun the other ranks wait.
      int status = 0;
      std::string err;
      if (world.isRoot()) {
        try {
          status = coloc::checkCase(check);
        } catch (const coloc::Error& e) {
          err = e.what();
          status = 2;
        }
        if (!err.empty()) std::fprintf(stderr, "coloc: error: %s\n", err.c_str());
        std::fflush(stdout);
      }
      return world.max(status);
    }
    if (app.got_subcommand("snapshot")) {  // (only when main() did not see it first)
      if (world.isRoot()) snapshot = snapshotJob;
      return 0;
    }
    if (app.got_subcommand("plan")) {
      if (world.size() != 1)
        throw coloc::Error("coloc plan runs in one process: start it without mpirun -n N");
      return coloc::planCase(planOpts);
    }
  } catch (const coloc::Error& e) {
    // keys, check and plan: the same verdict on every rank (check and plan work in one process).
    if (world.isRoot()) std::fprintf(stderr, "coloc: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    // Not an input error: something only this rank saw. End everyone rather than hang.
    coloc::abortAll(std::string("unexpected exception: ") + e.what());
  }
  coloc::installStopSignals();
  // What escapes runCase is an input error found before its phases (the case file): the same
  // on every rank. Agreed all the same, so that a rank that failed alone cannot hang the others
  // (it waits run.failure_wait_s at most; coloc/core/failure.hpp).
  const coloc::FailureChannel channel(world);
  std::string err;
  int code = 0;
  try {
    return coloc::runCase(world, opts, snapshot);
  } catch (const coloc::IoError& e) {
    err = e.what();
    code = coloc::kIoErrorStatus;
  } catch (const coloc::Error& e) {
    err = e.what();
    code = coloc::kInputErrorStatus;
  } catch (const std::exception& e) {
    err = std::string("unexpected exception: ") + e.what();
    code = coloc::kRunFailedStatus;
  }
  const auto v = channel.agree(err, code);
  if (world.isRoot()) std::fprintf(stderr, "coloc: error: %s\n", v.message.c_str());
  return v.code;
}

}  // namespace

// The snapshot (output.snapshot, `coloc snapshot`) runs a Python script in a child process. A
// child started from inside a live MPI process is not safe on every fabric: fork() copies the
// registered (pinned) memory of InfiniBand verbs and similar transports copy-on-write, and Open
// MPI warns of it or the child corrupts the parent's transfers. So the run only records on rank 0
// that a picture is due, and main() draws it after MPI_Finalize, when no fabric state is left,
// through posix_spawn (no shell; glibc starts the child without copying the address space).
// `coloc snapshot` is post-processing of a finished job: it is dispatched before MPI_Init and
// needs no MPI at all (a login node without a launcher, no singleton start-up).
int main(int argc, char** argv) {
  if (argc > 1 && std::string_view(argv[1]) == "snapshot")
    return coloc::snapshotCommand(argc, argv);
  std::optional<coloc::SnapshotJob> snapshot;
  int status = 0;
  {
    coloc::MpiSession mpi(&argc, &argv);
    status = mpiMain(argc, argv, snapshot);
  }  // MPI_Finalize
  if (snapshot) {
    const int drawn = coloc::drawSnapshot(*snapshot);
    if (status == 0) status = drawn;
  }
  return status;
}
