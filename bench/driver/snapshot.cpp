// output.snapshot and `coloc snapshot` (snapshot.hpp).
#include "snapshot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <vector>

#include "coloc/io/output.hpp"
#include "data_dir.hpp"
#include "run_log.hpp"

extern char** environ;

namespace coloc {
namespace {

namespace fs = std::filesystem;

/// snapshot.py of the installed data (PREFIX/share/coloc/scripts) or of the source tree.
fs::path snapshotScript() {
  return dataDir() / "scripts" / "snapshot.py";
}

/// The exit status of a child as a shell gives it: its own, or 128 + the signal that ended it.
int exitStatus(int waitStatus) {
  if (WIFEXITED(waitStatus)) return WEXITSTATUS(waitStatus);
  if (WIFSIGNALED(waitStatus)) return 128 + WTERMSIG(waitStatus);
  return -1;
}

/// What runCapturing() returns: the command's exit status (128 + the signal that ended it), or
/// -1 with `error` saying why it could not be run.
struct Captured {
  int status = -1;
  std::string error;
};

/// Starts `argv` (argv[0] looked up in PATH unless it holds a '/') with its stdout and stderr
/// on one pipe, each line passed to `line`, and waits for it.
template <class F>
Captured runCapturing(const std::vector<std::string>& args, F&& line) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return {-1, std::strerror(errno)};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);  // dup2 clears close-on-exec
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  pid_t pid = -1;
  std::fflush(stdout);
  std::fflush(stderr);
  const int rc = args[0].find('/') == std::string::npos
                     ? ::posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ)
                     : ::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (rc != 0) {
    ::close(fds[0]);
    return {-1, std::strerror(rc)};
  }
  if (std::FILE* in = ::fdopen(fds[0], "r")) {
    char text[1024];
    while (std::fgets(text, sizeof text, in)) line(text);
    std::fclose(in);
  } else {
    ::close(fds[0]);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return {-1, std::strerror(errno)};
  return {exitStatus(status), {}};
}

}  // namespace

std::optional<SnapshotJob> snapshotDue(const Config& cfg, const std::string& outDir, bool quiet) {
  const OutputOptions o = outputOptionsFromConfig(cfg, outDir);
  if (!cfg.boolean("output.snapshot") || !o.fields || o.intervalSteps <= 0) return std::nullopt;
  SnapshotJob job;
  job.dataDir = o.dir;
  job.png = (fs::path(outDir) / "snapshot.png").string();
  job.report = (fs::path(outDir) / "report.json").string();
  job.quiet = quiet;
  job.logPath = (fs::path(outDir) / "log.txt").string();
  job.ofRun = true;
  return job;
}

int drawSnapshot(const SnapshotJob& job) {
  // A run's log was closed with the run: appended to again (no line of the script lost).
  RunLog log(true);
  if (!job.logPath.empty()) {
    try {
      log.reopen(job.logPath);
    } catch (const std::exception& e) {
      log.err("coloc: warning: {}\n", e.what());
    }
  }
  const fs::path script = snapshotScript();
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  std::vector<std::string> args{python, script.string(), job.dataDir};
  if (job.step >= 0) args.insert(args.end(), {"--step", std::to_string(job.step)});
  if (!job.png.empty()) args.insert(args.end(), {"--png", job.png});
  if (!job.report.empty()) args.insert(args.end(), {"--report", job.report});
  if (job.full) args.emplace_back("--full");
  // Which script drew it (the installed one or the source tree's), in the run's log only.
  if (job.ofRun) log.file("coloc: drawing snapshot.png with {}\n", script.string());
  // What the script says goes to the terminal (unless quiet) and the log.
  const Captured ran = runCapturing(args, [&](const char* line) {
    if (job.quiet)
      log.file("{}", line);
    else
      log.out("{}", line);
  });
  const int rc = ran.status;
  if (!job.ofRun) {
    if (rc < 0) log.err("coloc: error: cannot run {}: {}\n", python, ran.error);
    return rc < 0 ? 1 : rc;
  }
  if (rc != 0)
    log.err(
        "coloc: warning: no snapshot.png ({} exited with status {}); the run's output "
        "is complete (set output.snapshot=false to skip the picture)\n",
        script.string(), rc);
  return 0;
}

CLI::App* addSnapshotCommand(CLI::App& app, SnapshotJob& job) {
  auto* cmd = app.add_subcommand(
      "snapshot",
      "draw OUT_DIR/snapshot.png from a finished run's last output (bench/scripts/snapshot.py, "
      "as output.snapshot does at the end of a run); one process, no mpirun");
  cmd->add_option("out_dir", job.dataDir,
                  "the run's output folder (its fields_NNNNNN.h5 and report.json)")
      ->required();
  cmd->add_option("--png", job.png, "the picture to write (default: OUT_DIR/snapshot.png)");
  cmd->add_option("--step", job.step, "the output step to draw (default: the last one)");
  cmd->add_flag("--full", job.full, "the whole box (default: cropped a margin above the bed)");
  return cmd;
}

int snapshotCommand(int argc, char** argv) {
  CLI::App app{"coloc snapshot: a picture of a finished run, without MPI"};
  app.require_subcommand(1);
  SnapshotJob job;
  addSnapshotCommand(app, job);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    if (code != 0) std::cerr << "Run 'coloc snapshot --help' for usage.\n";
    return code == 0 ? 0 : 2;
  }
  return drawSnapshot(job);
}

}  // namespace coloc
