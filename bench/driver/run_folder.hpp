// The folders a `coloc run` writes to (--out, output.dir): the lock that keeps a second run out
// while this one lasts, the checks that keep the checkpoint inside its folder and off the run's
// own files and off the --restart file, and the clean-up of what an earlier run of coloc left
// unfinished (docs/robustness.md, "What is kept on disk"). Rank 0 only; the driver agrees on the
// outcome with the other ranks.
#pragma once

#include <string>
#include <vector>

#include "coloc/io/checkpoint_file.hpp"

namespace coloc {

/// The run's folders and the names it writes there.
struct RunFolders {
  std::string outDir;          // --out: report.json, series.csv, snapshot.png, rebalance.tmp.h5
  std::string dataDir;         // output.dir: fields, particles, .xmf and the checkpoint
  std::string checkpointFile;  // output.checkpoint_file, relative to dataDir ({step} kept)
};

/// An exclusive lock (flock) on DIR/.coloc.lock of each folder, held while the object lives
/// (the kernel drops it when the process ends, however it ends: no stale lock). The file says
/// who holds it (pid, host, start time, case).
class FolderLocks {
 public:
  FolderLocks() = default;
  ~FolderLocks();
  FolderLocks(const FolderLocks&) = delete;
  FolderLocks& operator=(const FolderLocks&) = delete;
  /// Locks `dir` (an existing folder); throws ConfigError naming `key` (--out, output.dir) and
  /// the run that holds it when another process does; IoError when the lock file cannot be made.
  void lock(const std::string& dir, const std::string& key, const std::string& casePath);

 private:
  std::vector<int> fds_;
};

/// Throws ConfigError naming output.checkpoint_file when the checkpoint's folder leaves dataDir
/// through a symbolic link, and naming --restart when `restart` is one of the files the run
/// writes or removes in its folders (other than its own checkpoint name). The folders exist.
void checkRunFiles(const RunFolders& f, const std::string& restart);

/// Removes what would mislead about this run: the previous run's report.json and series.csv,
/// and the temporary files that only coloc itself makes (report.json.tmp, series.csv.tmp,
/// fields.xmf.tmp, fields_NNNNNN.h5.tmp, <checkpoint>.tmp, rebalance.tmp.h5, ...) and that a
/// killed run left. Nothing else: other programs' files stay. Checkpoints and output are kept.
void removeStaleFiles(const RunFolders& f);

}  // namespace coloc
