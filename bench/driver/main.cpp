// coloc — the command-line driver.
//
//   coloc run CASE.json [--set key.path=value ...] [--out DIR] [--restart CHECKPOINT.h5]
//   coloc keys            every case-file key, its type, default, range and meaning
//   coloc --help
//
// Errors in the input are found identically on every rank: rank 0 prints one message naming the
// key, and every rank exits with status 2. Nothing waits in a collective. A run that fails inside
// the time loop (a blow-up) exits with status 3 on every rank, an output that cannot be written
// with 4, a run stopped by SIGTERM/SIGINT with 128 + the signal (bench/driver/run.hpp,
// docs/robustness.md).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "coloc/core/comm.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"
#include "run.hpp"

int main(int argc, char** argv) {
  coloc::MpiSession mpi(&argc, &argv);
  const coloc::Comm world = coloc::Comm::world();

  CLI::App app{
      "coloc: co-located partitions CFD-DEM mini-app (fluid cells and the particles in\n"
      "the same region live on the same MPI rank). Run with mpirun -n N coloc run CASE."};
  app.require_subcommand(1);
  app.set_version_flag("--version", coloc::kVersionString);
  coloc::RunOptions opts;
  auto* run = app.add_subcommand("run", "run a case file and write DIR/report.json");
  run->add_option("case", opts.casePath, "case file (JSON, // comments allowed)")->required();
  run->add_option("--set", opts.overrides,
                  "override a case key, e.g. --set run.steps=20 (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  run->add_option("--out", opts.outDir, "output directory (default: out/<case name>)");
  run->add_flag("--quiet", opts.quiet, "no progress lines");
  run->add_option("--restart", opts.restart,
                  "continue from this checkpoint (output.checkpoint_*) instead of the case's "
                  "initial condition, on any rank count; run.steps/run.end_time count from the "
                  "start of the original run");
  app.add_subcommand("keys", "list every case-file key with type, default, range and meaning");

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

  if (app.got_subcommand("keys")) {
    if (world.isRoot()) std::cout << coloc::describeKeys();
    return 0;
  }
  coloc::installStopSignals();
  // What escapes runCase is an input error found before its phases (the case file): the same
  // on every rank. Agreed all the same, so that a rank that failed alone cannot hang the others
  // (it waits run.failure_wait_s at most; coloc/core/failure.hpp).
  const coloc::FailureChannel channel(world);
  std::string err;
  int code = 0;
  try {
    return coloc::runCase(world, opts);
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
